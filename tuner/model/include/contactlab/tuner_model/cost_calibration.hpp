// Fits the schedule model's MachineCosts to a few timed runs, once per machine and loop kind.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "contactlab/kernels/variant.hpp"
#include "contactlab/tuner_model/schedule_model.hpp"

namespace contactlab::tuner {

// One measured detection loop.
struct TimedRun {
  // iteration_work() of the variant that was run; not owned: the caller keeps it alive.
  WorkView work;
  int threads = 1;
  Schedule schedule;
  double seconds = 0.0;  // detection time T_c (a median of repetitions), without setup T_s
};

struct CalibrationResult {
  MachineCosts costs;
  // sqrt(mean(((predicted - measured) / measured)^2)) over the runs, with the fitted costs.
  double rms_relative_error = 0.0;
  double max_relative_error = 0.0;
  int rounds = 0;  // fits made (the critical threads are re-found after each)
  // Names of the constants that no run exercises (e.g. seconds_per_grab without a dynamic or
  // guided run): they keep the fallback's value.
  std::vector<std::string> unidentified;
};

// The model is linear in the constants for a fixed critical (slowest) thread of each run, so
// the fit alternates: find each run's critical thread under the current costs, fit all
// constants to those threads by non-negative least squares on relative errors (runs of 10 ms
// and of 10 s weigh alike), with Huber weights so that a disturbed run cannot drag the fit;
// repeat until the costs settle. Starts from `fallback`.
// To identify every constant, include: several thread counts, 1 thread with a small static
// chunk (separates per-chunk cost from break cost), dynamic or guided runs (grabs), both
// small and large chunks, and scenes where homes, builds and iterations are not proportional
// (dense cells beside sparse ones; empty cells in a cell loop). Throws std::invalid_argument for no
// runs, a run with threads < 1, seconds <= 0 or not finite, or an invalid schedule.
CalibrationResult calibrate_costs(std::span<const TimedRun> runs,
                                  const MachineCosts& fallback = MachineCosts{});

}  // namespace contactlab::tuner
