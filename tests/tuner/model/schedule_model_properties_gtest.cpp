// Randomised properties (rapidcheck, fixed seeds) of the schedule model over random work
// vectors, thread counts and schedules: the work is conserved, every iteration runs exactly
// once, and the greedy simulation keeps Graham's list-scheduling bound.
#include <gtest/gtest.h>
#include <rapidcheck.h>

#include <algorithm>
#include <cstdint>
#include <numeric>
#include <vector>

#include "contactlab/tuner_model/chunk_search.hpp"
#include "contactlab/tuner_model/schedule_model.hpp"
#include "rapidcheck_seeded.hpp"

namespace contactlab::tuner {
using test::check_with_seed;
namespace {

struct Case {
  std::vector<std::uint32_t> work;
  int threads = 1;
  Schedule schedule;
};

rc::Gen<Case> cases() {
  return rc::gen::apply(
      [](std::vector<std::uint32_t> work, int threads, int kind, int chunk) {
        Case c;
        c.work = std::move(work);
        c.threads = threads;
        c.schedule.kind = static_cast<ScheduleKind>(kind);
        c.schedule.chunk = c.schedule.kind == ScheduleKind::kStatic ? chunk : std::max(chunk, 1);
        return c;
      },
      rc::gen::container<std::vector<std::uint32_t>>(rc::gen::inRange<std::uint32_t>(0, 60)),
      rc::gen::inRange(1, 9), rc::gen::inRange(0, 3), rc::gen::inRange(0, 40));
}

std::uint64_t total(const std::vector<std::uint32_t>& work) {
  return std::accumulate(work.begin(), work.end(), std::uint64_t{0});
}

TEST(ScheduleModelProperties, EveryIterationRunsExactlyOnce) {
  check_with_seed(1, 300, [] {
    const Case c = *cases();
    const ScheduleOutcome outcome =
        simulate_schedule(c.work, c.threads, c.schedule, MachineCosts::tests_only(), true);
    std::vector<int> runs(c.work.size(), 0);
    for (const ChunkAssignment& chunk : outcome.chunks) {
      RC_ASSERT(chunk.begin < chunk.end);
      RC_ASSERT(chunk.thread >= 0 && chunk.thread < c.threads);
      for (std::uint64_t i = chunk.begin; i < chunk.end; ++i) ++runs[i];
    }
    RC_ASSERT(std::all_of(runs.begin(), runs.end(), [](int count) { return count == 1; }));
    std::uint64_t tests = 0, iterations = 0, chunks = 0;
    for (const ThreadShare& share : outcome.threads) {
      tests += share.tests;
      iterations += share.iterations;
      chunks += share.chunks;
      RC_ASSERT(share.stream_breaks <= share.chunks);
    }
    RC_ASSERT(tests == total(c.work));
    RC_ASSERT(iterations == c.work.size());
    RC_ASSERT(chunks == outcome.chunks.size());
    RC_ASSERT(outcome.test_imbalance >= 0.0);
    RC_ASSERT(outcome.test_imbalance <= 1.0 - 1.0 / c.threads + 1e-12);
  });
}

TEST(ScheduleModelProperties, SelfSchedulingKeepsGrahamsBound) {
  // A thread takes its last chunk when it is the least loaded, at most total / P, so it ends
  // by total / P + the largest chunk.
  check_with_seed(2, 300, [] {
    Case c = *cases();
    if (c.schedule.kind == ScheduleKind::kStatic)
      c.schedule = {ScheduleKind::kDynamic, std::max(c.schedule.chunk, 1)};
    const ScheduleOutcome outcome =
        simulate_schedule(c.work, c.threads, c.schedule, MachineCosts::tests_only(), true);
    std::uint64_t largest_chunk = 0;
    for (const ChunkAssignment& chunk : outcome.chunks) {
      largest_chunk = std::max<std::uint64_t>(
          largest_chunk, std::accumulate(c.work.begin() + static_cast<std::ptrdiff_t>(chunk.begin),
                                         c.work.begin() + static_cast<std::ptrdiff_t>(chunk.end),
                                         std::uint64_t{0}));
    }
    RC_ASSERT(static_cast<double>(outcome.max_thread_tests) <=
              static_cast<double>(total(c.work)) / c.threads + static_cast<double>(largest_chunk) +
                  1e-9);
  });
}

TEST(ScheduleModelProperties, GuidedChunksShrinkAndCoverTheLoop) {
  check_with_seed(3, 300, [] {
    const auto iterations = *rc::gen::inRange<std::uint64_t>(0, 5000);
    const int threads = *rc::gen::inRange(1, 17);
    const int chunk = *rc::gen::inRange(1, 100);
    const auto sizes =
        self_scheduling_chunk_sizes(iterations, threads, {ScheduleKind::kGuided, chunk});
    RC_ASSERT(std::accumulate(sizes.begin(), sizes.end(), std::uint64_t{0}) == iterations);
    for (std::size_t j = 0; j < sizes.size(); ++j) {
      RC_ASSERT(sizes[j] >= 1);
      if (j > 0) RC_ASSERT(sizes[j] <= sizes[j - 1]);
      if (j + 1 < sizes.size()) RC_ASSERT(sizes[j] >= static_cast<std::uint64_t>(chunk));
    }
  });
}

TEST(ScheduleModelProperties, OneThreadDoesEverythingInOneStream) {
  check_with_seed(4, 200, [] {
    Case c = *cases();
    c.threads = 1;
    const ScheduleOutcome outcome = simulate_schedule(c.work, 1, c.schedule, MachineCosts{});
    RC_ASSERT(outcome.threads[0].tests == total(c.work));
    RC_ASSERT(outcome.threads[0].stream_breaks == (c.work.empty() ? 0u : 1u));
    RC_ASSERT(outcome.imbalance == 0.0);
  });
}

TEST(ScheduleModelProperties, MedianIntervalContainsTheMedian) {
  check_with_seed(5, 300, [] {
    const auto samples = *rc::gen::nonEmpty(rc::gen::container<std::vector<double>>(
        rc::gen::map(rc::gen::inRange(0, 1000000), [](int v) { return v * 1e-6; })));
    const MedianInterval interval = median_interval(samples);
    const double m = median(samples);
    RC_ASSERT(interval.low <= m);
    RC_ASSERT(m <= interval.high);
    RC_ASSERT(interval.lower_rank + interval.upper_rank == samples.size() + 1);
    RC_ASSERT(interval.coverage >= 0.0);
    RC_ASSERT(interval.coverage <= 1.0);
  });
}

}  // namespace
}  // namespace contactlab::tuner
