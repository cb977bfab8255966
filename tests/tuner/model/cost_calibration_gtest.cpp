// Calibration recovers known MachineCosts from synthetic timed runs made with the model
// itself: exactly without noise, closely with noise, and undisturbed by one bad run.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "contactlab/kernels/rng.hpp"
#include "contactlab/tuner_model/cost_calibration.hpp"

namespace contactlab::tuner {
namespace {

// Distinct from the defaults, so that a fit that stays at its starting point fails.
MachineCosts true_costs() {
  MachineCosts costs;
  costs.seconds_per_test = 1.5e-9;
  costs.seconds_per_iteration = 4e-9;
  costs.seconds_per_home = 3e-8;
  costs.seconds_per_build = 9e-8;
  costs.seconds_per_static_chunk = 8e-9;
  costs.seconds_per_grab = 3e-7;
  costs.seconds_per_stream_break = 2e-7;
  costs.seconds_per_cold_test = 5e-9;
  costs.seconds_per_region = 1e-5;
  return costs;
}

double uniform(Xoshiro256& rng) { return static_cast<double>(rng.next() >> 11) * 0x1.0p-53; }

struct SyntheticWork {
  std::vector<std::uint32_t> tests, homes;
  std::vector<std::uint8_t> builds;
  WorkView view() const { return {tests, homes, builds}; }
};

// Particle loop in cell order over cells of 1 to 40 particles, each testing its cell partners;
// the first particle of a cell builds the neighbour ranges.
SyntheticWork particle_loop_work() {
  Xoshiro256 rng(11);
  SyntheticWork work;
  while (work.tests.size() < 4000) {
    const auto size = static_cast<std::uint32_t>(1 + rng.next() % 40);
    work.tests.insert(work.tests.end(), size, size - 1);
    work.builds.push_back(1);
    work.builds.insert(work.builds.end(), size - 1, 0);
  }
  work.homes.assign(work.tests.size(), 1);
  return work;
}

// Cell loop: most cells empty, a few heavy.
SyntheticWork cell_loop_work() {
  Xoshiro256 rng(12);
  SyntheticWork work;
  work.tests.assign(3000, 0);
  work.homes.assign(3000, 0);
  work.builds.assign(3000, 0);
  for (std::size_t i = 0; i < work.tests.size(); ++i) {
    if (uniform(rng) < 0.4) {
      const auto homes = static_cast<std::uint32_t>(1 + rng.next() % 70);
      work.homes[i] = homes;
      work.tests[i] = homes * (homes - 1);
      work.builds[i] = 1;
    }
  }
  return work;
}

struct Synthetic {
  std::vector<SyntheticWork> works;
  std::vector<TimedRun> runs;
};

Synthetic synthetic_runs(const MachineCosts& costs, const std::vector<Schedule>& schedules) {
  Synthetic synthetic;
  synthetic.works = {particle_loop_work(), cell_loop_work()};
  for (const auto& work : synthetic.works) {
    for (const int threads : {1, 2, 4}) {
      for (const Schedule& schedule : schedules) {
        const double seconds =
            simulate_schedule(work.view(), threads, schedule, costs).makespan_seconds;
        synthetic.runs.push_back({work.view(), threads, schedule, seconds});
      }
    }
  }
  return synthetic;
}

std::vector<Schedule> every_kind() {
  return {{ScheduleKind::kStatic, 0},  {ScheduleKind::kStatic, 1},  {ScheduleKind::kStatic, 4},
          {ScheduleKind::kStatic, 16}, {ScheduleKind::kStatic, 64}, {ScheduleKind::kStatic, 256},
          {ScheduleKind::kDynamic, 1}, {ScheduleKind::kDynamic, 8}, {ScheduleKind::kDynamic, 64},
          {ScheduleKind::kGuided, 1},  {ScheduleKind::kGuided, 16}};
}

void expect_costs_near(const MachineCosts& fitted, const MachineCosts& truth, double relative) {
  EXPECT_NEAR(fitted.seconds_per_test, truth.seconds_per_test, relative * truth.seconds_per_test);
  EXPECT_NEAR(fitted.seconds_per_iteration, truth.seconds_per_iteration,
              relative * truth.seconds_per_iteration);
  EXPECT_NEAR(fitted.seconds_per_home, truth.seconds_per_home, relative * truth.seconds_per_home);
  EXPECT_NEAR(fitted.seconds_per_build, truth.seconds_per_build,
              relative * truth.seconds_per_build);
  EXPECT_NEAR(fitted.seconds_per_static_chunk, truth.seconds_per_static_chunk,
              relative * truth.seconds_per_static_chunk);
  EXPECT_NEAR(fitted.seconds_per_grab, truth.seconds_per_grab, relative * truth.seconds_per_grab);
  EXPECT_NEAR(fitted.seconds_per_stream_break, truth.seconds_per_stream_break,
              relative * truth.seconds_per_stream_break);
  EXPECT_NEAR(fitted.seconds_per_cold_test, truth.seconds_per_cold_test,
              relative * truth.seconds_per_cold_test);
  EXPECT_NEAR(fitted.seconds_per_region, truth.seconds_per_region,
              relative * truth.seconds_per_region);
}

TEST(CalibrateCosts, RecoversKnownConstantsExactly) {
  const Synthetic synthetic = synthetic_runs(true_costs(), every_kind());
  const CalibrationResult result = calibrate_costs(synthetic.runs);
  expect_costs_near(result.costs, true_costs(), 1e-6);
  EXPECT_LT(result.rms_relative_error, 1e-9);
  EXPECT_TRUE(result.unidentified.empty());
  EXPECT_GE(result.rounds, 1);
}

TEST(CalibrateCosts, StaysCloseUnderMeasurementNoise) {
  Synthetic synthetic = synthetic_runs(true_costs(), every_kind());
  Xoshiro256 rng(99);
  for (TimedRun& run : synthetic.runs) run.seconds *= 1.0 + 0.02 * (2.0 * uniform(rng) - 1.0);
  const CalibrationResult result = calibrate_costs(synthetic.runs);
  EXPECT_LT(result.rms_relative_error, 0.02);
  // What the fit is for: it predicts the noise-free times within the noise.
  for (const TimedRun& run : synthetic.runs) {
    const double truth =
        simulate_schedule(run.work, run.threads, run.schedule, true_costs()).makespan_seconds;
    const double fitted =
        simulate_schedule(run.work, run.threads, run.schedule, result.costs).makespan_seconds;
    EXPECT_NEAR(fitted, truth, 0.02 * truth);
  }
  // Tests and homes trade against each other within the noise (a dense cell's tests grow with
  // its homes), but the constants that carry most of the time stay close.
  EXPECT_NEAR(result.costs.seconds_per_test, true_costs().seconds_per_test,
              0.15 * true_costs().seconds_per_test);
  EXPECT_NEAR(result.costs.seconds_per_grab, true_costs().seconds_per_grab,
              0.2 * true_costs().seconds_per_grab);
}

TEST(CalibrateCosts, OneDisturbedRunDoesNotDragTheFit) {
  Synthetic synthetic = synthetic_runs(true_costs(), every_kind());
  synthetic.runs[5].seconds *= 3.0;  // e.g. another program took the cores during that run
  const CalibrationResult result = calibrate_costs(synthetic.runs);
  expect_costs_near(result.costs, true_costs(), 0.05);
  EXPECT_GT(result.max_relative_error, 0.5);  // the disturbed run stands out
}

TEST(CalibrateCosts, ConstantsNoRunExercisesKeepTheFallback) {
  const Synthetic synthetic = synthetic_runs(
      true_costs(),
      {{ScheduleKind::kStatic, 0}, {ScheduleKind::kStatic, 4}, {ScheduleKind::kStatic, 64}});
  MachineCosts fallback;
  fallback.seconds_per_grab = 4.2e-7;
  const CalibrationResult result = calibrate_costs(synthetic.runs, fallback);
  EXPECT_EQ(result.unidentified, (std::vector<std::string>{"seconds_per_grab"}));
  EXPECT_DOUBLE_EQ(result.costs.seconds_per_grab, 4.2e-7);
  EXPECT_LT(result.rms_relative_error, 1e-6);
}

TEST(CalibrateCosts, RejectsBadRuns) {
  EXPECT_THROW(calibrate_costs(std::vector<TimedRun>{}), std::invalid_argument);
  const std::vector<std::uint32_t> work(10, 1);
  try {
    calibrate_costs(std::vector<TimedRun>{{work, 2, {ScheduleKind::kStatic, 0}, 0.0}});
    FAIL() << "no exception";
  } catch (const std::invalid_argument& error) {
    EXPECT_EQ(std::string(error.what()).rfind("calibrate_costs: run 0", 0), 0u) << error.what();
  }
  EXPECT_THROW(calibrate_costs(std::vector<TimedRun>{{work, 0, {ScheduleKind::kStatic, 0}, 1.0}}),
               std::invalid_argument);
  EXPECT_THROW(calibrate_costs(std::vector<TimedRun>{{work, 2, {ScheduleKind::kGuided, 0}, 1.0}}),
               std::invalid_argument);
}

// The weighing alone, as the model prices it: simulate_balanced with every loop constant 0.
double weighing_seconds(const SyntheticWork& work, int threads, double per_iteration,
                        double per_build) {
  MachineCosts costs;
  for (const auto& [name, member] : kMachineCostFields) costs.*member = 0.0;
  costs.seconds_per_weighed_iteration = per_iteration;
  costs.seconds_per_weighed_build = per_build;
  return simulate_schedule(work.view(), threads, {ScheduleKind::kBalanced, 0}, costs)
      .makespan_seconds;
}

TEST(CalibrateWeighing, RecoversKnownConstantsFromADenseAndASparseLoop) {
  const std::vector<SyntheticWork> works{particle_loop_work(), cell_loop_work()};
  std::vector<WeighRun> runs;
  for (const auto& work : works) {
    for (const int threads : {2, 3, 16}) {
      runs.push_back({work.view(), threads, weighing_seconds(work, threads, 2e-9, 3e-8)});
    }
  }
  const WeighingFit fit = calibrate_weighing(runs);
  EXPECT_NEAR(fit.seconds_per_iteration, 2e-9, 1e-6 * 2e-9);
  EXPECT_NEAR(fit.seconds_per_build, 3e-8, 1e-6 * 3e-8);
  EXPECT_LT(fit.rms_relative_error, 1e-9);
}

TEST(CalibrateWeighing, ANegativeConstantIsNeverFitted) {
  // Times that fall as the builds grow would fit a negative per-build constant: it stays 0 and
  // the iterations take the time.
  const SyntheticWork sparse = cell_loop_work(), dense = particle_loop_work();
  const std::vector<WeighRun> runs{{sparse.view(), 2, 1e-6}, {dense.view(), 2, 8e-6}};
  const WeighingFit fit = calibrate_weighing(runs);
  EXPECT_GE(fit.seconds_per_iteration, 0.0);
  EXPECT_GE(fit.seconds_per_build, 0.0);
  EXPECT_GT(fit.seconds_per_iteration + fit.seconds_per_build, 0.0);
}

TEST(CalibrateWeighing, RejectsBadRuns) {
  EXPECT_THROW(calibrate_weighing(std::vector<WeighRun>{}), std::invalid_argument);
  const std::vector<std::uint32_t> work(10, 1);
  try {
    calibrate_weighing(std::vector<WeighRun>{{work, 1, 1e-6}});
    FAIL() << "no exception";
  } catch (const std::invalid_argument& error) {
    EXPECT_EQ(std::string(error.what()).rfind("calibrate_weighing: run 0 has threads = 1", 0), 0u)
        << error.what();
  }
  EXPECT_THROW(calibrate_weighing(std::vector<WeighRun>{{work, 2, 0.0}}), std::invalid_argument);
}

}  // namespace
}  // namespace contactlab::tuner
