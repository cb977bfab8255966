// The schedule model against layouts worked out by hand (in the spirit of Takagi et al.'s
// Fig. 6), against libgomp itself for the static schedules, and the cost model term by term.
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cstdint>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "contactlab/kernels/balanced_blocks.hpp"
#include "contactlab/tuner_model/schedule_model.hpp"

namespace contactlab::tuner {
namespace {

using Tests = std::vector<std::uint64_t>;

// 20 particles, reordered by cell, in four cells of 4, 3, 4 and 9 particles; only same-cell
// pairs are tested, so each particle's work is the number of its cell partners (its cell's
// size - 1), as in the paper's Fig. 6 (whose own counts 12/45 and 27/30 cannot be rebuilt
// from its text). Total: 4*3 + 3*2 + 4*3 + 9*8 = 12 + 6 + 12 + 72 = 102 tests.
//   iteration: 0 1 2 3 | 4 5 6 | 7 8 9 10 | 11 ... 19
//   work:      3 3 3 3 | 2 2 2 | 3 3 3  3 |  8 ...  8
std::vector<std::uint32_t> fig6_layout() {
  std::vector<std::uint32_t> work;
  for (const std::uint32_t cell_size : {4u, 3u, 4u, 9u})
    work.insert(work.end(), cell_size, cell_size - 1);
  return work;
}

TEST(Fig6Layout, HasTheStatedWork) {
  const auto work = fig6_layout();
  ASSERT_EQ(work.size(), 20u);
  std::uint64_t total = 0;
  for (const auto w : work) total += w;
  EXPECT_EQ(total, 102u);
}

TEST(Fig6Layout, StaticBlockGivesTheDenseCellToOneThread) {
  // q = 20 / 2 = 10: thread 0 = iterations 0..9 = 4*3 + 3*2 + 3*3 = 27,
  //                  thread 1 = iterations 10..19 = 3 + 9*8 = 75.
  EXPECT_EQ(thread_tests(fig6_layout(), 2, {ScheduleKind::kStatic, 0}), (Tests{27, 75}));
  const ScheduleOutcome outcome = simulate_schedule(fig6_layout(), 2, {ScheduleKind::kStatic, 0});
  EXPECT_EQ(outcome.max_thread_tests, 75u);
  EXPECT_DOUBLE_EQ(outcome.test_imbalance, (75.0 - 51.0) / 75.0);  // mean = 102 / 2 = 51
}

TEST(Fig6Layout, StaticCyclicSpreadsTheDenseCell) {
  // static,1: even iterations to thread 0: 3+3+2+2+3 (0..8) + 3 (10) + 4*8 (12..18) = 48;
  //           odd ones to thread 1:       3+3+2+3+3 (1..9) + 5*8 (11..19)          = 54.
  EXPECT_EQ(thread_tests(fig6_layout(), 2, {ScheduleKind::kStatic, 1}), (Tests{48, 54}));
  // static,2: chunks [0,2)=6 [2,4)=6 [4,6)=4 [6,8)=5 [8,10)=6 [10,12)=11 then four of 16;
  //           thread 0 = 6+4+6+16+16 = 48, thread 1 = 6+5+11+16+16 = 54.
  EXPECT_EQ(thread_tests(fig6_layout(), 2, {ScheduleKind::kStatic, 2}), (Tests{48, 54}));
  // static,3: chunks [0,3)=9 [3,6)=7 [6,9)=8 [9,12)=14 [12,15)=24 [15,18)=24 [18,20)=16;
  //           thread 0 = 9+8+24+16 = 57, thread 1 = 7+14+24 = 45.
  EXPECT_EQ(thread_tests(fig6_layout(), 2, {ScheduleKind::kStatic, 3}), (Tests{57, 45}));
  // static,5: chunks [0,5)=14 [5,10)=13 [10,15)=35 [15,20)=40;
  //           thread 0 = 14+35 = 49, thread 1 = 13+40 = 53.
  EXPECT_EQ(thread_tests(fig6_layout(), 2, {ScheduleKind::kStatic, 5}), (Tests{49, 53}));
}

TEST(Fig6Layout, DynamicGivesEachChunkToTheFirstFreeThread) {
  // dynamic,3 on the test clock: chunks 9, 7, 8, 14, 24, 24, 16 in loop order.
  //   t0 takes 9 (free at 9), t1 takes 7 (7); t1 takes 8 (15); t0 takes 14 (23);
  //   t1 takes 24 (39); t0 takes 24 (47); t1 takes 16 (55).
  const ScheduleOutcome outcome = simulate_schedule(fig6_layout(), 2, {ScheduleKind::kDynamic, 3},
                                                    MachineCosts::tests_only(), true);
  EXPECT_EQ(outcome.threads[0].tests, 47u);
  EXPECT_EQ(outcome.threads[1].tests, 55u);
  const std::vector<ChunkAssignment> expected = {{0, 3, 0},   {3, 6, 1},   {6, 9, 1},  {9, 12, 0},
                                                 {12, 15, 1}, {15, 18, 0}, {18, 20, 1}};
  EXPECT_EQ(outcome.chunks, expected);
}

TEST(Fig6Layout, GuidedHalvesWhatIsLeft) {
  // guided,1 with 2 threads: sizes ceil(20/2)=10, ceil(10/2)=5, ceil(5/2)=3, 1, 1.
  //   [0,10)=27 -> t0 (27); [10,15)=35 -> t1 (35); [15,18)=24 -> t0 (51);
  //   [18,19)=8 -> t1 (43); [19,20)=8 -> t1 (51).
  EXPECT_EQ(thread_tests(fig6_layout(), 2, {ScheduleKind::kGuided, 1}), (Tests{51, 51}));
  // guided,4: sizes 10, max(4, 5)=5, max(4, 3)=4, then 1 left (smaller than 4: the rest).
  //   [0,10)=27 -> t0; [10,15)=35 -> t1; [15,19)=32 -> t0 (59); [19,20)=8 -> t1 (43).
  EXPECT_EQ(thread_tests(fig6_layout(), 2, {ScheduleKind::kGuided, 4}), (Tests{59, 43}));
}

TEST(Fig6Layout, BalancedBlocksEqualTheTestsPlusTheHomesCost) {
  // Weights: tests + kHomeTests (200) a home: 203 x 4 | 202 x 3 | 203 x 4 | 208 x 9, 4102 in
  // all. Thread 1 begins where the prefix first reaches 2051: after iteration 10 (2230).
  static_assert(kHomeTests == 200);
  const ScheduleOutcome outcome = simulate_schedule(fig6_layout(), 2, {ScheduleKind::kBalanced, 0},
                                                    MachineCosts::tests_only(), true);
  const std::vector<ChunkAssignment> expected = {{0, 11, 0}, {11, 20, 1}};
  EXPECT_EQ(outcome.chunks, expected);
  EXPECT_EQ(thread_tests(fig6_layout(), 2, {ScheduleKind::kBalanced, 0}), (Tests{30, 72}));
  EXPECT_THROW(simulate_schedule(fig6_layout(), 2, {ScheduleKind::kBalanced, 8}),
               std::invalid_argument);
}

// One thread does not weigh (the detector runs it as the block): the same time as the block, at
// costs that would price a weighing.
TEST(Fig6Layout, BalancedAtOneThreadIsTheBlock) {
  MachineCosts costs = MachineCosts::tests_only();
  costs.seconds_per_iteration = 1.0;
  costs.seconds_per_build = 2.0;
  const double block =
      simulate_schedule(fig6_layout(), 1, {ScheduleKind::kStatic, 0}, costs).makespan_seconds;
  EXPECT_DOUBLE_EQ(
      simulate_schedule(fig6_layout(), 1, {ScheduleKind::kBalanced, 0}, costs).makespan_seconds,
      block);
  // At two threads each thread first weighs its slice: 10 iterations at 1 s, and its builds.
  EXPECT_GT(
      simulate_schedule(fig6_layout(), 2, {ScheduleKind::kBalanced, 0}, costs).makespan_seconds,
      10.0);
}

// The weighing at its own constants where they are set (the emulation's measured weighing), at
// the loop's otherwise: 10 iterations a slice at 1 s, or at 0.25 s.
TEST(Fig6Layout, BalancedWeighingTakesItsOwnConstantsWhereSet) {
  MachineCosts costs = MachineCosts::tests_only();
  costs.seconds_per_iteration = 1.0;
  const Schedule balanced{ScheduleKind::kBalanced, 0};
  const double at_loop_costs =
      simulate_schedule(fig6_layout(), 2, balanced, costs).makespan_seconds;
  costs.seconds_per_weighed_iteration = 0.25;
  costs.seconds_per_weighed_build = 0.0;
  const double at_own = simulate_schedule(fig6_layout(), 2, balanced, costs).makespan_seconds;
  EXPECT_DOUBLE_EQ(at_loop_costs - at_own, 10 * (1.0 - 0.25));
}

TEST(StaticBlock, GivesTheFirstRemainderThreadsOneMore) {
  // 7 iterations on 3 threads: q = 2, r = 1: [0,3) [3,5) [5,7).
  const std::vector<std::uint32_t> work(7, 1);
  const ScheduleOutcome outcome =
      simulate_schedule(work, 3, {ScheduleKind::kStatic, 0}, MachineCosts::tests_only(), true);
  const std::vector<ChunkAssignment> expected = {{0, 3, 0}, {3, 5, 1}, {5, 7, 2}};
  EXPECT_EQ(outcome.chunks, expected);
  // More threads than iterations: the last threads get nothing (and no chunk).
  const ScheduleOutcome sparse =
      simulate_schedule(std::vector<std::uint32_t>(2, 5), 4, {ScheduleKind::kStatic, 0});
  EXPECT_EQ(sparse.threads[2].chunks, 0u);
  EXPECT_EQ(sparse.threads[3].tests, 0u);
  EXPECT_DOUBLE_EQ(sparse.test_imbalance, (5.0 - 2.5) / 5.0);
}

TEST(DynamicSchedule, TiesGoToTheThreadWithFewerChunksThenTheLowestId) {
  // dynamic,1, work 4 1 1 1 1 1 1 1 on 2 threads: t0 takes the 4; t1 takes 1..4 (free at 4);
  // tie at 4: t0 has 1 chunk, t1 has 4 -> t0 takes 5 (5); t1 takes 6 (5); tie -> t0 takes 7.
  const std::vector<std::uint32_t> work = {4, 1, 1, 1, 1, 1, 1, 1};
  const ScheduleOutcome outcome =
      simulate_schedule(work, 2, {ScheduleKind::kDynamic, 1}, MachineCosts::tests_only(), true);
  EXPECT_EQ(outcome.threads[0].tests, 6u);
  EXPECT_EQ(outcome.threads[1].tests, 5u);
  std::vector<int> owner;
  for (const ChunkAssignment& chunk : outcome.chunks) owner.push_back(chunk.thread);
  EXPECT_EQ(owner, (std::vector<int>{0, 1, 1, 1, 1, 0, 1, 0}));
  // Chunks without work still go round: every thread starts with one.
  const ScheduleOutcome empty_chunks =
      simulate_schedule(std::vector<std::uint32_t>(4, 0), 4, {ScheduleKind::kDynamic, 1});
  for (const ThreadShare& share : empty_chunks.threads) EXPECT_EQ(share.chunks, 1u);
}

TEST(SelfSchedulingChunkSizes, FollowLibgompGuidedFormula) {
  // 100 iterations, 4 threads, guided,1: q = ceil(n / 4) of what is left.
  EXPECT_EQ(self_scheduling_chunk_sizes(100, 4, {ScheduleKind::kGuided, 1}),
            (Tests{25, 19, 14, 11, 8, 6, 5, 3, 3, 2, 1, 1, 1, 1}));
  // guided,5: never below 5 except the remainder.
  EXPECT_EQ(self_scheduling_chunk_sizes(40, 4, {ScheduleKind::kGuided, 5}),
            (Tests{10, 8, 6, 5, 5, 5, 1}));
  EXPECT_EQ(self_scheduling_chunk_sizes(10, 3, {ScheduleKind::kDynamic, 4}), (Tests{4, 4, 2}));
  EXPECT_TRUE(self_scheduling_chunk_sizes(0, 3, {ScheduleKind::kDynamic, 4}).empty());
  EXPECT_THROW(self_scheduling_chunk_sizes(10, 3, {ScheduleKind::kStatic, 4}),
               std::invalid_argument);
}

// Who runs each iteration under libgomp with the schedule set at run time, as the detector does.
std::vector<int> libgomp_owners(std::size_t iterations, int threads, const Schedule& schedule) {
  const omp_sched_t kind = schedule.kind == ScheduleKind::kStatic    ? omp_sched_static
                           : schedule.kind == ScheduleKind::kDynamic ? omp_sched_dynamic
                                                                     : omp_sched_guided;
  omp_set_schedule(kind, schedule.chunk);
  std::vector<int> owner(iterations, -1);
  const auto n = static_cast<long>(iterations);
#pragma omp parallel for schedule(runtime) num_threads(threads)
  for (long i = 0; i < n; ++i) owner[static_cast<std::size_t>(i)] = omp_get_thread_num();
  return owner;
}

std::vector<int> model_owners(std::size_t iterations, int threads, const Schedule& schedule) {
  const std::vector<std::uint32_t> work(iterations, 1);
  const ScheduleOutcome outcome =
      simulate_schedule(work, threads, schedule, MachineCosts::tests_only(), true);
  std::vector<int> owner(iterations, -1);
  for (const ChunkAssignment& chunk : outcome.chunks) {
    for (std::uint64_t i = chunk.begin; i < chunk.end; ++i) owner[i] = chunk.thread;
  }
  return owner;
}

TEST(Libgomp, StaticPartitionsMatchTheModelExactly) {
  for (const std::size_t iterations : {0u, 1u, 7u, 20u, 1001u}) {
    for (const int threads : {1, 2, 3, 4}) {
      for (const int chunk : {0, 1, 2, 3, 7, 64}) {
        const Schedule schedule{ScheduleKind::kStatic, chunk};
        EXPECT_EQ(libgomp_owners(iterations, threads, schedule),
                  model_owners(iterations, threads, schedule))
            << iterations << " iterations, " << threads << " threads, static," << chunk;
      }
    }
  }
}

TEST(Libgomp, SelfScheduledRunsStartOnModelChunkBoundaries) {
  // Which thread grabs which chunk depends on timing, but the chunk boundaries do not: every
  // maximal run of one thread's iterations must start on a boundary of the modelled sizes.
  for (const Schedule schedule :
       {Schedule{ScheduleKind::kGuided, 1}, Schedule{ScheduleKind::kGuided, 3},
        Schedule{ScheduleKind::kDynamic, 7}}) {
    const std::size_t iterations = 1000;
    const int threads = 4;
    std::vector<bool> boundary(iterations + 1, false);
    std::uint64_t start = 0;
    for (const std::uint64_t size : self_scheduling_chunk_sizes(iterations, threads, schedule)) {
      boundary[start] = true;
      start += size;
    }
    const std::vector<int> owner = libgomp_owners(iterations, threads, schedule);
    for (std::size_t i = 0; i < iterations; ++i) {
      if (i == 0 || owner[i] != owner[i - 1]) {
        EXPECT_TRUE(boundary[i]) << to_string(schedule) << ": a run starts at " << i;
      }
    }
  }
}

// Costs in distinct powers of ten, so each term shows in its own digits.
MachineCosts decimal_costs() {
  MachineCosts costs;
  costs.seconds_per_test = 1;
  costs.seconds_per_iteration = 10;
  costs.seconds_per_static_chunk = 100;
  costs.seconds_per_grab = 1e3;
  costs.seconds_per_stream_break = 1e4;
  costs.seconds_per_cold_test = 1e5;
  costs.seconds_per_home = 1e6;
  costs.seconds_per_region = 1e7;
  costs.seconds_per_build = 1e8;
  return costs;
}

// A tests-only work view counts one home and one build per iteration.
constexpr double kTenHomesAndBuilds = 10 * 1e6 + 10 * 1e8;

TEST(CostModel, PricesEveryTermOfStaticBlock) {
  const ScheduleOutcome outcome =
      simulate_schedule(fig6_layout(), 2, {ScheduleKind::kStatic, 0}, decimal_costs());
  // Thread 0: 27 tests, 10 iterations (homes, builds), 1 chunk, 1 break whose first iteration
  // has 3 tests.
  EXPECT_DOUBLE_EQ(outcome.threads[0].seconds,
                   27 + 10 * 10 + 100 + 1e4 + 3 * 1e5 + kTenHomesAndBuilds);
  // Thread 1: 75 tests, 10 iterations, 1 chunk, 1 break at iteration 10 (3 tests).
  EXPECT_DOUBLE_EQ(outcome.threads[1].seconds,
                   75 + 10 * 10 + 100 + 1e4 + 3 * 1e5 + kTenHomesAndBuilds);
  EXPECT_DOUBLE_EQ(outcome.makespan_seconds,
                   1e7 + 75 + 10 * 10 + 100 + 1e4 + 3 * 1e5 + kTenHomesAndBuilds);
  EXPECT_EQ(outcome.threads[0].grabs, 0u);
}

TEST(CostModel, CountsBreaksOnlyWhereAThreadJumps) {
  // One thread, static,4: five chunks, one contiguous stream: one break (the start).
  const ScheduleOutcome one =
      simulate_schedule(fig6_layout(), 1, {ScheduleKind::kStatic, 4}, decimal_costs());
  EXPECT_EQ(one.threads[0].chunks, 5u);
  EXPECT_EQ(one.threads[0].stream_breaks, 1u);
  EXPECT_DOUBLE_EQ(one.threads[0].seconds,
                   102 + 20 * 10 + 5 * 100 + 1e4 + 3 * 1e5 + 2 * kTenHomesAndBuilds);
  // Two threads, static,5: every chunk starts a new stream; thread 1's chunks begin at
  // iterations 5 (2 tests) and 15 (8 tests).
  const ScheduleOutcome two =
      simulate_schedule(fig6_layout(), 2, {ScheduleKind::kStatic, 5}, decimal_costs());
  EXPECT_EQ(two.threads[1].stream_breaks, 2u);
  EXPECT_EQ(two.threads[1].cold_tests, 10u);
  EXPECT_DOUBLE_EQ(two.threads[1].seconds,
                   53 + 10 * 10 + 2 * 100 + 2 * 1e4 + 10 * 1e5 + kTenHomesAndBuilds);
}

TEST(CostModel, SelfScheduledLoopsPayAGrabPerChunkPlusTheLastEmptyOne) {
  const ScheduleOutcome outcome =
      simulate_schedule(fig6_layout(), 1, {ScheduleKind::kDynamic, 5}, decimal_costs());
  EXPECT_EQ(outcome.threads[0].chunks, 4u);
  EXPECT_EQ(outcome.threads[0].grabs, 5u);
  EXPECT_EQ(outcome.threads[0].stream_breaks, 1u);
  EXPECT_DOUBLE_EQ(outcome.threads[0].seconds,
                   102 + 20 * 10 + 5 * 1e3 + 1e4 + 3 * 1e5 + 2 * kTenHomesAndBuilds);
  EXPECT_TRUE(outcome.self_scheduled);
}

// The Fig. 6 layout as a particle loop in cell order: the first particle of each cell
// (iterations 0, 4, 7, 11) builds the neighbour ranges, the others reuse them, unless a chunk
// that does not continue its thread's stream starts mid-cell.
TEST(CostModel, ParticleLoopBuildsOncePerCellAndAtBreaksMidCell) {
  const std::vector<std::uint32_t> tests = fig6_layout();
  const std::vector<std::uint32_t> homes(20, 1);
  std::vector<std::uint8_t> builds(20, 0);
  for (const int first : {0, 4, 7, 11}) builds[first] = 1;
  const WorkView work(tests, homes, builds);
  // One thread, static,4: one stream, 4 builds.
  EXPECT_EQ(simulate_schedule(work, 1, {ScheduleKind::kStatic, 4}).threads[0].builds, 4u);
  // Two threads, static,5: thread 0 runs [0,5) (builds at 0 and 4) and [10,15) (11, and 10
  // starts mid-cell after a break): 4; thread 1 runs [5,10) (7, and 5 mid-cell) and [15,20)
  // (15 mid-cell): 3.
  const ScheduleOutcome two = simulate_schedule(work, 2, {ScheduleKind::kStatic, 5});
  EXPECT_EQ(two.threads[0].builds, 4u);
  EXPECT_EQ(two.threads[1].builds, 3u);
  EXPECT_EQ(two.threads[0].homes, 10u);
}

// One PreparedWork serves every schedule, with the same outcome as a fresh one per schedule.
TEST(CostModel, PreparedWorkIsSharedAcrossSchedules) {
  const std::vector<std::uint32_t> tests{0, 6, 0, 0, 12, 1, 1};
  const std::vector<std::uint32_t> homes{0, 3, 0, 0, 4, 1, 1};
  const std::vector<std::uint8_t> builds{0, 1, 0, 0, 1, 1, 1};
  const WorkView view(tests, homes, builds);
  const PreparedWork prepared(view);
  EXPECT_EQ(prepared.tests(1, 5), 18u);
  EXPECT_EQ(prepared.homes(0, 7), 9u);
  EXPECT_EQ(prepared.builds(2, 4), 0u);
  EXPECT_EQ(PreparedWork(WorkView(tests)).homes(2, 5), 3u);  // tests alone: 1 per iteration
  for (const Schedule& schedule :
       {Schedule{ScheduleKind::kStatic, 0}, Schedule{ScheduleKind::kStatic, 2},
        Schedule{ScheduleKind::kDynamic, 1}, Schedule{ScheduleKind::kGuided, 1}}) {
    const ScheduleOutcome shared = simulate_schedule(prepared, 2, schedule, decimal_costs(), true);
    const ScheduleOutcome fresh = simulate_schedule(view, 2, schedule, decimal_costs(), true);
    EXPECT_EQ(shared.chunks, fresh.chunks);
    EXPECT_DOUBLE_EQ(shared.makespan_seconds, fresh.makespan_seconds);
  }
}

// A cell loop over five cells, three empty: empty cells cost an iteration, no home, no build,
// even where a chunk starts on them.
TEST(CostModel, CellLoopPaysHomesAndBuildsOnlyForOccupiedCells) {
  const std::vector<std::uint32_t> tests{0, 6, 0, 0, 12};
  const std::vector<std::uint32_t> homes{0, 3, 0, 0, 4};
  const std::vector<std::uint8_t> builds{0, 1, 0, 0, 1};
  const ScheduleOutcome outcome =
      simulate_schedule(WorkView(tests, homes, builds), 2, {ScheduleKind::kStatic, 1});
  EXPECT_EQ(outcome.threads[0].iterations, 3u);  // cells 0, 2, 4
  EXPECT_EQ(outcome.threads[0].homes, 4u);
  EXPECT_EQ(outcome.threads[0].builds, 1u);
  EXPECT_EQ(outcome.threads[1].homes, 3u);  // cells 1, 3
  EXPECT_EQ(outcome.threads[1].builds, 1u);
  EXPECT_THROW(WorkView(tests, std::vector<std::uint32_t>(4, 1), builds), std::invalid_argument);
}

TEST(CostModel, ChunkSequenceRepeatsItsLastSize) {
  const ScheduleOutcome outcome =
      simulate_chunk_sequence(fig6_layout(), 2, Tests{10, 4}, MachineCosts::tests_only(), true);
  // [0,10)=27 -> t0; [10,14)=27 -> t1; tie at 27, equal chunks -> t0 takes [14,18)=32 (59);
  // t1 takes [18,20)=16 (43).
  const std::vector<ChunkAssignment> expected = {{0, 10, 0}, {10, 14, 1}, {14, 18, 0}, {18, 20, 1}};
  EXPECT_EQ(outcome.chunks, expected);
  EXPECT_THROW(simulate_chunk_sequence(fig6_layout(), 2, Tests{}), std::invalid_argument);
  EXPECT_THROW(simulate_chunk_sequence(fig6_layout(), 2, Tests{3, 0}), std::invalid_argument);
}

TEST(ThreadImbalance, IsMaxMinusMeanOverMax) {
  EXPECT_DOUBLE_EQ(imbalance(std::vector<double>{1, 1, 1}), 0.0);
  EXPECT_DOUBLE_EQ(imbalance(std::vector<double>{4, 0, 0, 0}), 0.75);
  EXPECT_DOUBLE_EQ(imbalance(std::vector<std::uint64_t>{27, 75}), 24.0 / 75.0);
  EXPECT_DOUBLE_EQ(imbalance(std::vector<double>{}), 0.0);
  EXPECT_DOUBLE_EQ(imbalance(std::vector<double>{0, 0}), 0.0);
}

TEST(Log2ChunkGrid, DoublesUpToTheLargest) {
  EXPECT_EQ(log2_chunk_grid(16), (std::vector<int>{1, 2, 4, 8, 16}));
  EXPECT_EQ(log2_chunk_grid(20), (std::vector<int>{1, 2, 4, 8, 16}));
  EXPECT_EQ(log2_chunk_grid().size(), 17u);  // 1 .. 65536
  EXPECT_THROW(log2_chunk_grid(0), std::invalid_argument);
}

// Chunks that leave every thread at least 16 of them: 300,000 iterations at 2 threads keep
// 1 .. 8192 (9375 allowed), at 16 threads 1 .. 1024 (1171); a loop too short for any keeps the
// smallest chunk.
TEST(BalancedChunkGrid, KeepsSixteenChunksAThread) {
  const std::vector<int> grid = log2_chunk_grid(65536);
  EXPECT_EQ(balanced_chunk_grid(grid, 300000, 2), log2_chunk_grid(8192));
  EXPECT_EQ(balanced_chunk_grid(grid, 300000, 16), log2_chunk_grid(1024));
  EXPECT_EQ(balanced_chunk_grid(grid, 32 * 16, 32), (std::vector<int>{1}));
  EXPECT_EQ(balanced_chunk_grid(grid, 10, 4), (std::vector<int>{1}));
  const std::vector<int> coarse = {64, 256, 1024};
  EXPECT_EQ(balanced_chunk_grid(coarse, 1000, 4), (std::vector<int>{64}));
}

TEST(PredictBestChunk, BalancesImbalanceAgainstChunkCosts) {
  // 1000 particles: 800 cheap ones, then a dense tail of 200 with 100 tests each.
  std::vector<std::uint32_t> work(800, 1);
  work.insert(work.end(), 200, 100);
  MachineCosts costs = MachineCosts::tests_only();
  costs.seconds_per_test = 1e-9;
  costs.seconds_per_stream_break = 1e-7;
  const std::vector<int> candidates = log2_chunk_grid(1024);
  const ChunkPrediction prediction =
      predict_best_chunk(work, 4, ScheduleKind::kStatic, costs, candidates);
  ASSERT_EQ(prediction.candidates.size(), candidates.size());
  // Small chunks pay 1000/k breaks, the largest ones leave the dense tail to one thread.
  EXPECT_GT(prediction.best_chunk, 1);
  EXPECT_LT(prediction.best_chunk, 256);
  for (const CandidatePrediction& candidate : prediction.candidates) {
    EXPECT_GE(candidate.predicted_seconds, prediction.best_seconds) << candidate.chunk;
  }
  // k = 1024: one chunk, all on thread 0: 800 + 200 * 100 tests and one break.
  EXPECT_NEAR(prediction.candidates.back().predicted_seconds, 20800e-9 + 1e-7, 1e-15);
  EXPECT_NEAR(prediction.candidates.back().imbalance, 0.75, 1e-12);
}

TEST(PredictBestChunk, PrefersTheLargerChunkOnTies) {
  const std::vector<std::uint32_t> work(64, 1);  // every chunk below splits 16 / 16 / 16 / 16
  const ChunkPrediction cyclic = predict_best_chunk(
      work, 4, ScheduleKind::kStatic, MachineCosts::tests_only(), std::vector<int>{1, 2, 4, 8, 16});
  EXPECT_EQ(cyclic.best_chunk, 16);
  EXPECT_DOUBLE_EQ(cyclic.best_seconds, 16.0);
  // Block partition counts as the largest chunk.
  const ChunkPrediction with_block = predict_best_chunk(
      work, 4, ScheduleKind::kStatic, MachineCosts::tests_only(), std::vector<int>{0, 4, 16});
  EXPECT_EQ(with_block.best_chunk, 0);
}

TEST(ScheduleModelErrors, NameTheFunctionAndTheValues) {
  const auto work = fig6_layout();
  try {
    simulate_schedule(work, 0, {ScheduleKind::kStatic, 0});
    FAIL() << "no exception";
  } catch (const std::invalid_argument& error) {
    EXPECT_EQ(std::string(error.what()).rfind("simulate_schedule: threads = 0", 0), 0u)
        << error.what();
  }
  EXPECT_THROW(simulate_schedule(work, 2, {ScheduleKind::kDynamic, 0}), std::invalid_argument);
  EXPECT_THROW(simulate_schedule(work, 2, {ScheduleKind::kStatic, -1}), std::invalid_argument);
  EXPECT_THROW(
      predict_best_chunk(work, 2, ScheduleKind::kStatic, MachineCosts{}, std::vector<int>{}),
      std::invalid_argument);
  EXPECT_THROW(
      predict_best_chunk(work, 2, ScheduleKind::kGuided, MachineCosts{}, std::vector<int>{0}),
      std::invalid_argument);
}

}  // namespace
}  // namespace contactlab::tuner
