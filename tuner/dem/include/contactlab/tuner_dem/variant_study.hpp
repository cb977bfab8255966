// Speed against error of the force variants: each runs the same steps from the same start as
// the deterministic default (ordered), timed, and its positions are compared with the
// default's, particle by particle (by stable id).
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "contactlab/dem/engine.hpp"

namespace contactlab::dem {

struct VariantStudyRow {
  ForceVariant variant;
  int threads = 1;
  double seconds = 0.0;  // wall time of the steps
  // Of it, the force pass (pairs, reduction, walls, update: what the force model predicts),
  // per step.
  double force_seconds_per_step = 0.0;
  double particle_steps_per_s = 0.0;
  double speedup = 0.0;        // over the ordered default at the same thread count
  double max_deviation = 0.0;  // max |x - x_ordered| over particles, in diameters
  bool bit_identical = false;  // every position equal to the default's
};

// `make_engine(variant, threads)` builds the engine at the common start (e.g. a config's
// particles, or a checkpoint restored). The reference is the ordered default at each thread
// count; every variant runs `steps` steps after one untimed step (first touches).
std::vector<VariantStudyRow> variant_study(
    const std::function<std::unique_ptr<Engine>(const ForceVariant&, int)>& make_engine,
    const std::vector<ForceVariant>& variants, const std::vector<int>& thread_counts,
    std::uint64_t steps);

}  // namespace contactlab::dem
