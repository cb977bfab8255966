// The ordered pass's row ranges (RowRanges): split by work (pairs plus particles) before any
// thread was timed, moved towards the faster threads by their measured seconds per unit of
// work, every start a multiple of eight in [0, n], in order; a new thread count starts over. And
// the pass's signals between threads (RowsDone).
#include <gtest/gtest.h>

#include <atomic>
#include <cstdint>
#include <thread>
#include <vector>

#include "contactlab/dem/row_ranges.hpp"

namespace contactlab::dem {
namespace {

// CSR offsets of n particles with pairs_of(a) pairs each.
template <class F>
std::vector<std::uint32_t> rows_of(std::size_t n, F pairs_of) {
  std::vector<std::uint32_t> rows(n + 1, 0);
  for (std::size_t a = 0; a < n; ++a) rows[a + 1] = rows[a] + pairs_of(a);
  return rows;
}

void expect_valid(std::span<const std::size_t> bounds, std::size_t n, std::size_t threads) {
  ASSERT_EQ(bounds.size(), threads + 1);
  EXPECT_EQ(bounds.front(), 0u);
  EXPECT_EQ(bounds.back(), n);
  for (std::size_t t = 1; t < threads; ++t) {
    EXPECT_LE(bounds[t - 1], bounds[t]) << t;
    EXPECT_TRUE(bounds[t] % RowRanges::kAlign == 0 || bounds[t] == n) << t << ": " << bounds[t];
  }
}

TEST(DemRowRanges, FirstSplitIsByPairsAndParticles) {
  // 10 pairs in each of the first 500 rows, none after: the work is 500 * 11 + 500 = 6000, and
  // half of it, 3000, lies before particle 272.7; 272 (2992) is the nearest multiple of 8.
  const auto rows = rows_of(1000, [](std::size_t a) { return a < 500 ? 10u : 0u; });
  RowRanges ranges;
  const auto bounds = ranges.plan(rows, rows.size() - 1, 2);
  expect_valid(bounds, 1000, 2);
  EXPECT_EQ(bounds[1], 272u);
}

TEST(DemRowRanges, EveryThreadCountGivesOrderedAlignedStarts) {
  for (const std::size_t n : {0u, 5u, 100u, 1001u}) {
    const auto rows = rows_of(n, [](std::size_t a) { return static_cast<std::uint32_t>(a % 7); });
    for (const std::size_t threads : {1u, 2u, 3u, 16u, 64u}) {
      RowRanges ranges;
      expect_valid(ranges.plan(rows, rows.size() - 1, threads), n, threads);
    }
  }
  RowRanges before_any_list;  // no rows: split by particles
  const auto by_count = before_any_list.plan({}, 100, 3);
  expect_valid(by_count, 100, 3);
  EXPECT_EQ(by_count[1], 32u);  // 33.3 particles: 32 is the nearest multiple of 8
}

TEST(DemRowRanges, ASlowerThreadGetsLessWork) {
  const auto rows = rows_of(3000, [](std::size_t) { return 4u; });  // 5 units a particle
  RowRanges ranges;
  auto bounds = ranges.plan(rows, rows.size() - 1, 2);
  EXPECT_EQ(bounds[1], 1504u);  // 7500 of 15000 units: 1500; 1496 and 1504 as near, the later
  // Thread 0 took twice as long for its half: it runs at about half the speed of thread 1.
  ranges.record(0, 2.0);
  ranges.record(1, 1.0);
  ranges.learn(rows);
  EXPECT_DOUBLE_EQ(ranges.seconds_per_unit()[0], 2.0 / (5 * 1504));
  EXPECT_DOUBLE_EQ(ranges.seconds_per_unit()[1], 1.0 / (5 * 1496));
  bounds = ranges.plan(rows, rows.size() - 1, 2);
  expect_valid(bounds, 3000, 2);
  // Speeds 3760 and 7480 units a second: thread 0's share is 0.3345 of 15000 units, 5017.8,
  // which lies before particle 1003.6; 1000 is the nearest multiple of 8.
  EXPECT_EQ(bounds[1], 1000u);
}

TEST(DemRowRanges, OneStepMovesASpeedByAtMostTwiceAndIsSmoothed) {
  const auto rows = rows_of(800, [](std::size_t) { return 1u; });
  RowRanges ranges;
  ranges.plan(rows, rows.size() - 1, 2);  // 400 and 400 particles: 800 units each
  ranges.record(0, 800e-9);
  ranges.record(1, 800e-9);
  ranges.learn(rows);
  EXPECT_DOUBLE_EQ(ranges.seconds_per_unit()[0], 1e-9);
  ranges.plan(rows, rows.size() - 1, 2);
  ranges.record(0, 100 * 800e-9);  // a step preempted: read as twice the rate, weighted 0.2
  ranges.record(1, 800e-9);
  ranges.learn(rows);
  EXPECT_DOUBLE_EQ(ranges.seconds_per_unit()[0], 0.8e-9 + 0.2 * 2e-9);
  EXPECT_DOUBLE_EQ(ranges.seconds_per_unit()[1], 1e-9);
}

TEST(DemRowRanges, ANewThreadCountStartsOver) {
  const auto rows = rows_of(800, [](std::size_t) { return 1u; });
  RowRanges ranges;
  ranges.plan(rows, rows.size() - 1, 2);
  ranges.record(0, 3.0);
  ranges.record(1, 1.0);
  ranges.learn(rows);
  const auto three = ranges.plan(rows, rows.size() - 1, 3);  // nothing known of a team of three
  EXPECT_EQ(ranges.seconds_per_unit()[0], 0.0);
  EXPECT_EQ(three[1], 264u);  // 1600 / 3 units: 266.7 particles
}

// RowsDone: a wait returns only once the thread awaited announced that pass or a later one (and
// what it wrote before is seen), an earlier pass's signal does not count, and more threads than
// cores (each waiting on the next, as the ordered pass's ranges do) all get through.
TEST(DemRowsDone, AWaitSeesTheAnnouncedPassAndWhatCameBefore) {
  constexpr std::size_t kThreads = 8;  // on the 2-core machines: oversubscribed
  constexpr std::uint64_t kPasses = 200;
  RowsDone done;
  done.resize(kThreads);
  std::vector<std::atomic<std::uint64_t>> written(kThreads);  // relaxed: the signals order them
  std::atomic<int> wrong{0};
  std::vector<std::thread> team;
  for (std::size_t t = 0; t < kThreads; ++t) {
    team.emplace_back([&, t] {
      for (std::uint64_t pass = 1; pass <= kPasses; ++pass) {
        written[t].store(pass, std::memory_order_relaxed);  // published by the announce
        done.announce(t, pass);
        if (t + 1 < kThreads) {
          done.wait_for(t + 1, pass);
          // The next one's write of this pass (or of a later one, had it gone on).
          if (written[t + 1].load(std::memory_order_relaxed) < pass) ++wrong;
        }
        // The next pass may not start before the one after has read this one's write.
        if (t > 0) done.wait_for(t - 1, pass);
      }
    });
  }
  for (std::thread& thread : team) thread.join();
  EXPECT_EQ(wrong.load(), 0);
}

}  // namespace
}  // namespace contactlab::dem
