// The one place where tuning methods are registered, in the order tune() runs them (each may
// stand on those before it). The classic chunk formulas (chunk_formulas.hpp) are priced on the
// structure the last method tuned and verified beside them, under "classic:<formula>".
#include "contactlab/tuner_model/schedule_model.hpp"
#include "methods.hpp"

namespace contactlab::tuner {

const std::vector<std::unique_ptr<TuningMethod>>& tuning_methods() {
  static const std::vector<std::unique_ptr<TuningMethod>> methods = [] {
    std::vector<std::unique_ptr<TuningMethod>> m;
    m.push_back(make_model_method());
    m.push_back(make_search_method());
    m.push_back(make_exhaustive_method());
    return m;
  }();
  return methods;
}

Variant with_schedule(Variant structure, ScheduleKind kind, int chunk) {
  structure.schedule = Schedule{kind, chunk};
  return structure;
}

std::vector<Variant> structures_of(const TuneOptions& options) {
  return enumerate(VariantSpace{options.loops,
                                options.orders,
                                options.stencils,
                                {Schedule{}},
                                options.precisions,
                                options.grids});
}

std::vector<int> chunk_grid_of(MeasuredKernel& kernel, std::span<const int> grid,
                               std::size_t iterations, int threads) {
  double largest = static_cast<double>(iterations);
  kernel.max_over_parts(std::span<double>(&largest, 1));
  return balanced_chunk_grid(grid, static_cast<std::size_t>(largest), threads);
}

}  // namespace contactlab::tuner
