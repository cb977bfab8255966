// The exhaustive sweep (ground truth, with --exhaustive): every chunk of the grid for the
// search's structure and schedule kind, and with `static` its block too (no chunk size: one
// share per thread, thread 0's rows written in place), one timed run per point per round, each
// round in a new seeded order; its fastest point is the exhaustive best.
#include <omp.h>

#include "methods.hpp"

namespace contactlab::tuner {
namespace {

class ExhaustiveMethod final : public TuningMethod {
 public:
  std::string_view name() const override { return "exhaustive"; }
  bool times_runs() const override { return true; }
  bool enabled(const TuneOptions& options) const override { return options.exhaustive; }

  MethodEntry choose(TuningState& state) override {
    const double start = omp_get_wtime();
    const PricedStructure& tuned = state.tuned ? *state.tuned : *state.model_best;
    const ScheduleKind kind = state.tuned_kind;
    auto measure = [&](int chunk) {
      return state.kernel.samples(with_schedule(tuned.variant, kind, chunk), state.threads, 1);
    };
    ChunkSearchOptions options = state.search_options;
    options.rounds = state.options.exhaustive_rounds;
    // Without the block the sweep was no ground truth where the block wins: the model and the
    // search, which can choose it, came out 10 - 14 % faster than "the exhaustive best" on four
    // of the five study scenes (results/amd-epyc-2c/tuning, 2026-12-03).
    options.with_block = kind == ScheduleKind::kStatic;
    const ChunkSearchResult all = exhaustive_chunk_sweep(measure, options);
    nlohmann::json points = nlohmann::json::array();
    for (const ChunkMeasurement& m : all.measured) {
      points.push_back({{"chunk", m.chunk},
                        {"median_s", m.median_seconds},
                        {"ci95_low_s", m.interval.low},
                        {"ci95_high_s", m.interval.high}});
    }
    const Variant chosen = with_schedule(tuned.variant, kind, all.fastest_chunk);
    state.choices.emplace_back("exhaustive", chosen);
    MethodEntry entry;
    entry.method = "exhaustive";
    entry.variant = to_string(chosen);
    entry.chunk = all.fastest_chunk;
    entry.largest_equivalent_chunk = all.chosen_chunk;
    entry.rounds = state.options.exhaustive_rounds;
    entry.timed_runs = all.evaluations;
    entry.tuning_cost_s = omp_get_wtime() - start;
    entry.chunks_measured = points;
    return entry;
  }
};

}  // namespace

std::unique_ptr<TuningMethod> make_exhaustive_method() {
  return std::make_unique<ExhaustiveMethod>();
}

}  // namespace contactlab::tuner
