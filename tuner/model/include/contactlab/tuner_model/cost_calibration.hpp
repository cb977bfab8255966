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

// One measured weighing of the balanced schedule (DetectRun::weigh_s: until every thread had
// weighed its equal slice of `work`'s iterations, simulate_balanced's slices).
struct WeighRun {
  WorkView work;  // not owned, as TimedRun's
  int threads = 2;
  double seconds = 0.0;
};

struct WeighingFit {
  double seconds_per_iteration = 0.0;  // MachineCosts::seconds_per_weighed_iteration
  double seconds_per_build = 0.0;      // MachineCosts::seconds_per_weighed_build
  double rms_relative_error = 0.0;     // over the runs, with the fitted constants
};

// The weighing's constants: a slice's time is iterations x per_iteration + builds x
// per_build, the run's the slowest slice's; fitted by non-negative least squares on relative
// errors, the slowest slice found again under each fit until it stays. Scenes where the
// iterations and the builds are not proportional identify both (a dense and a sparse one);
// otherwise one of them takes all. Throws std::invalid_argument for no runs, a run with
// threads < 2 (one thread does not weigh), seconds <= 0 or not finite.
WeighingFit calibrate_weighing(std::span<const WeighRun> runs);

}  // namespace contactlab::tuner
