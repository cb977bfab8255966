// `dem run --variant auto [--retune]`: the force model's choice at the start and at every
// neighbour-list rebuild, and the log of which variant ran when (dem_command.cpp).
#pragma once

#include <fmt/core.h>
#include <omp.h>

#include <algorithm>
#include <cstdint>
#include <string>
#include <vector>

#include "contactlab/dem/engine.hpp"
#include "contactlab/kernels/atomic_file.hpp"
#include "contactlab/tuner_dem/force_model.hpp"

namespace contactlab::cli {

// `dem run --variant auto [--retune]`: the variant the force model chooses at the start and,
// with --retune, at every neighbour-list rebuild (no timed runs: the pair list priced with the
// calibrated costs), and the log of which variant ran when.
class VariantTuning {
 public:
  VariantTuning(const contactlab::dem::ForceCosts& costs, double margin)
      : costs_(costs), retuner_(costs, contactlab::dem::force_variants({1, 4, 16}), margin) {}

  void start(contactlab::dem::Engine& engine) {
    fmt::print("variant auto: force model calibrated by {} runs of {} steps ({:.1f} s)\n",
               costs_.calibration_runs, costs_.calibration_steps, costs_.calibration_seconds);
    decide(engine, true);
  }
  void after_steps(contactlab::dem::Engine& engine) {
    if (engine.rebuilds() == rebuilds_seen_) return;
    decide(engine, false);
  }
  void finish(const contactlab::dem::Engine& engine, double wall_s) {
    if (!log_.empty()) log_.back().end_step = engine.step_count();
    fmt::print(
        "variants ran ({} decisions at rebuilds, {:.3f} s of pricing, {:.2f} % of the run):\n",
        decisions_, pricing_s_, 100.0 * pricing_s_ / std::max(wall_s, 1e-9));
    for (const Entry& e : log_) {
      fmt::print("  steps {:>9} - {:<9} t = {:<10.6g} {}  (predicted gain {:+.1f} %)\n",
                 e.begin_step, e.end_step, e.time_s, contactlab::dem::to_string(e.variant),
                 100.0 * e.predicted_gain);
    }
  }
  void write_log(const std::string& path) const {
    write_file_atomically(path, [&](std::ostream& out) {
      out << "begin_step,end_step,time_s,variant,predicted_gain\n";
      for (const Entry& e : log_) {
        out << fmt::format("{},{},{:.9g},{},{:.6g}\n", e.begin_step, e.end_step, e.time_s,
                           contactlab::dem::to_string(e.variant), e.predicted_gain);
      }
    });
  }

 private:
  struct Entry {
    std::uint64_t begin_step = 0, end_step = 0;
    double time_s = 0.0;
    contactlab::dem::ForceVariant variant;
    double predicted_gain = 0.0;
  };
  void decide(contactlab::dem::Engine& engine, bool first) {
    const double t0 = omp_get_wtime();
    rebuilds_seen_ = engine.rebuilds();
    ++decisions_;
    // The start leaves the config's variant (the deterministic default unless it names one) by
    // the same rule as every later switch: only for a predicted gain above the margin. The
    // calibration times one run per structure, so predictions a few % apart are within its
    // noise; on hopper-small the start once took update=fused for a predicted 1.7 % and ran
    // 5.6 % behind the default it left (docs/dem.md).
    const contactlab::dem::ForceRetuner::Decision d =
        retuner_.decide(engine, engine.settings().force_variant);
    pricing_s_ += omp_get_wtime() - t0;
    if (first) {
      fmt::print(
          "variant auto: starts with {} (the model's best, {}, predicted {:+.1f} % faster "
          "than {}; margin {:.1f} %: the stated one or the calibration's spread, {:.1f} %, "
          "whichever is larger)\n",
          contactlab::dem::to_string(d.variant), contactlab::dem::to_string(d.best),
          100.0 * d.predicted_gain, contactlab::dem::to_string(engine.settings().force_variant),
          100.0 * retuner_.margin(), 100.0 * costs_.calibration_spread);
    }
    if (!first && !d.switched) return;
    engine.set_force_variant(d.variant);
    if (!log_.empty()) log_.back().end_step = engine.step_count();
    log_.push_back(
        {engine.step_count(), engine.step_count(), engine.time_s(), d.variant, d.predicted_gain});
    if (!first) {
      fmt::print("step {} (t = {:.6g} s): variant -> {} (predicted gain {:+.1f} %)\n",
                 engine.step_count(), engine.time_s(), contactlab::dem::to_string(d.variant),
                 100.0 * d.predicted_gain);
    }
  }

  contactlab::dem::ForceCosts costs_;
  contactlab::dem::ForceRetuner retuner_;
  std::uint64_t rebuilds_seen_ = 0, decisions_ = 0;
  double pricing_s_ = 0.0;
  std::vector<Entry> log_;
};

}  // namespace contactlab::cli
