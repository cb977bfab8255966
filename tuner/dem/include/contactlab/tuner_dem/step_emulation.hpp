// A DEM step at thread counts this machine does not have (the report's 8 threads, 16), for
// `dem profile --emulate`: the force pass replayed by the force model (force_model.hpp) with
// costs calibrated at one thread and anchored to the measured one-thread pass, the neighbour
// list and the integration split into a serial and a parallel part from their measured times at
// 1 and P threads. Every value is labelled emulated by its callers. Not modelled: memory
// bandwidth and shared caches as threads are added; the j sides that land in another thread's
// blocks (their cost exists only with several threads: a one-thread calibration prices them 0).
#pragma once

#include <vector>

#include "contactlab/dem/engine.hpp"
#include "contactlab/tuner_dem/force_model.hpp"

namespace contactlab::dem {

// Seconds per step by phase, measured at one thread count (medians over rounds).
struct MeasuredStep {
  int threads = 1;
  PhaseTimes per_step;
  double step_s = 0.0;  // wall time per step
};

struct EmulatedStep {
  int threads = 1;
  double neighbor_s = 0.0, force_s = 0.0, integrate_s = 0.0;
  double step_s() const { return neighbor_s + force_s + integrate_s; }
};

// `one` is the one-thread measurement (the anchor), `widest` the one at the most threads timed
// (the same as `one` on a one-core machine: the neighbour list and integration then count as
// serial). `costs` are calibrated at one thread. Throws InputError when `one` is not at one
// thread or its force pass took no time.
std::vector<EmulatedStep> emulate_steps(const ForceLoopWork& work, const ForceVariant& variant,
                                        const ForceCosts& costs, const MeasuredStep& one,
                                        const MeasuredStep& widest,
                                        const std::vector<int>& threads);

}  // namespace contactlab::dem
