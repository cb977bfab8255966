// The model: zero timed runs on the scene. The exact per-iteration work of every structure and
// the machine's calibrated costs price every schedule kind and chunk of the grid (libgomp's
// schedules simulated, schedule_model.hpp); its cost is the work profiles.
#include <omp.h>

#include <array>
#include <limits>

#include "contactlab/kernels/error.hpp"
#include "methods.hpp"

namespace contactlab::tuner {
namespace {

WorkView view_of(const LoopWork& work) { return {work.tests, work.homes, work.builds}; }

// The share of the whole output's copy time a variant pays at `threads`: the entries it copies,
// times `exchange` where its half stencil's threads pass their reverse entries on.
double output_share(MeasuredKernel& kernel, const Variant& variant, int threads, double exchange) {
  return kernel.copied_output_share(variant, threads) *
         (passes_reverse_entries_on(variant, threads) ? exchange : 1.0);
}

// The model's best schedule for one structure: every kind, every chunk of the grid, each with
// the loop's time and its share of `output_s` (the time to copy the whole output after the
// loop; a schedule may let the kernel write part of it in place). A kernel run by several
// processes (MPI ranks, each on its own work) is as fast as its slowest: each prediction is
// the maximum over the kernel's parts before the choice, so every part chooses alike.
std::pair<Variant, double> best_schedule(MeasuredKernel& kernel, const Variant& structure,
                                         WorkView work, int threads, const MachineCosts& costs,
                                         const std::vector<int>& grid, double output_s,
                                         double exchange) {
  const PreparedWork prepared(work);
  const std::array kinds{ScheduleKind::kStatic, ScheduleKind::kDynamic, ScheduleKind::kGuided,
                         ScheduleKind::kBalanced};
  std::vector<std::vector<int>> chunks;
  std::vector<double> seconds;
  const std::vector<int> balanced = chunk_grid_of(kernel, grid, work.tests.size(), threads);
  for (const auto kind : kinds) {
    // Balanced has its blocks and no chunk; static has the block besides its chunks.
    std::vector<int> candidates = kind == ScheduleKind::kBalanced ? std::vector<int>{0} : balanced;
    if (kind == ScheduleKind::kStatic) candidates.insert(candidates.begin(), 0);  // block
    for (const CandidatePrediction& c :
         predict_best_chunk(prepared, threads, kind, costs, candidates).candidates) {
      seconds.push_back(c.predicted_seconds +
                        output_s * output_share(kernel, with_schedule(structure, kind, c.chunk),
                                                threads, exchange));
    }
    chunks.push_back(std::move(candidates));
  }
  kernel.max_over_parts(seconds);
  // Within a kind the fastest, equal times preferring the larger chunk (block the largest), as
  // predict_best_chunk; across kinds the first fastest.
  auto locality_rank = [](int chunk) {
    return chunk == 0 ? std::numeric_limits<long long>::max() : static_cast<long long>(chunk);
  };
  std::pair<Variant, double> best{structure, std::numeric_limits<double>::infinity()};
  std::size_t at = 0;
  for (std::size_t k = 0; k < kinds.size(); ++k) {
    int best_chunk = chunks[k].front();
    double best_s = seconds[at];
    for (const int chunk : chunks[k]) {
      const double s = seconds[at++];
      if (s < best_s || (s == best_s && locality_rank(chunk) > locality_rank(best_chunk))) {
        best_chunk = chunk;
        best_s = s;
      }
    }
    if (best_s < best.second) best = {with_schedule(structure, kinds[k], best_chunk), best_s};
  }
  return best;
}

class ModelMethod final : public TuningMethod {
 public:
  std::string_view name() const override { return "model"; }
  bool times_runs() const override { return false; }

  MethodEntry choose(TuningState& state) override {
    const double start = omp_get_wtime();
    const TuneOptions& options = state.options;
    nlohmann::json table = nlohmann::json::array();
    // The same for every structure (the contacts do not depend on it): estimated once.
    const OutputEstimate output = state.kernel.estimated_output();
    for (const Variant& structure : structures_of(options)) {
      const auto found = state.calibration.structures.find(structure_key(structure));
      const bool calibrated = found != state.calibration.structures.end();
      PricedStructure s{structure,
                        state.kernel.iteration_work(structure, state.threads),
                        calibrated ? found->second.costs : MachineCosts{},
                        structure,
                        0.0,
                        calibrated ? found->second.output : std::vector<OutputCost>{}};
      const double copy_all_s = output_seconds(s.output, output, state.threads);
      const double exchange = exchange_factor(s.output, state.threads);
      std::tie(s.model_choice, s.predicted_s) =
          best_schedule(state.kernel, structure, view_of(s.work), state.threads, s.costs,
                        options.chunk_grid, copy_all_s, exchange);
      s.output_s = copy_all_s * output_share(state.kernel, s.model_choice, state.threads, exchange);
      table.push_back({{"variant", to_string(s.model_choice)},
                       {"predicted_s", s.predicted_s},
                       {"output_s", s.output_s}});
      state.structures.push_back(std::move(s));
    }
    // Single precision too: its variants find the exact contacts (pair_test.hpp's FloatBand).
    for (const PricedStructure& s : state.structures) {
      if (!state.model_best || s.predicted_s < state.model_best->predicted_s) state.model_best = &s;
    }
    if (!state.model_best) throw InputError("tune: no structure left to choose from");
    state.model_cost_s = omp_get_wtime() - start;

    // Other thread counts, from the model's structure.
    const PricedStructure& best = *state.model_best;
    for (const int p : options.predict_threads) {
      const auto [variant, seconds] = best_schedule(
          state.kernel, best.variant, view_of(best.work), p, best.costs, options.chunk_grid,
          output_seconds(best.output, output, p), exchange_factor(best.output, p));
      state.report.predictions.push_back(
          {p, to_string(variant), seconds,
           p > omp_get_num_procs() ? "predicted (model only: more threads than this machine has)"
                                   : "predicted (model only)"});
    }
    state.choices.emplace_back("model", best.model_choice);
    MethodEntry entry;
    entry.method = "model";
    entry.variant = to_string(best.model_choice);
    entry.chunk = best.model_choice.schedule.chunk;
    entry.predicted_s = best.predicted_s;
    entry.timed_runs = 0;
    entry.tuning_cost_s = state.model_cost_s;
    entry.structures = table;
    return entry;
  }
};

}  // namespace

std::unique_ptr<TuningMethod> make_model_method() { return std::make_unique<ModelMethod>(); }

}  // namespace contactlab::tuner
