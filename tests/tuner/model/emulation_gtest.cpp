// The emulation's pieces on hand-computed cases: the serial/parallel split of a phase, a trace
// anchored to its one-thread time and replayed (checked against libgomp's own deal of a real
// 2-thread loop over the same trace), the ranks' blocks of the replicated detection, and the
// network model of both MPI modes.
#include <gtest/gtest.h>
#include <omp.h>

#include <cstdint>
#include <stdexcept>
#include <vector>

#include "contactlab/tuner_model/emulation.hpp"

namespace contactlab::tuner {
namespace {

// Takagi et al.'s Fig. 6 layout (schedule_model_gtest.cpp): cells of 4, 3, 4 and 9 particles,
// each particle testing its cell partners. 102 tests in 20 iterations.
std::vector<std::uint32_t> fig6_trace() {
  std::vector<std::uint32_t> work;
  for (const std::uint32_t cell_size : {4u, 3u, 4u, 9u})
    work.insert(work.end(), cell_size, cell_size - 1);
  return work;
}

TEST(AmdahlPhase, FitsTwoPointsAndExtrapolates) {
  const AmdahlPhase phase = AmdahlPhase::fit(1.0, 2, 0.6);
  EXPECT_DOUBLE_EQ(phase.serial_s, 0.2);
  EXPECT_DOUBLE_EQ(phase.parallel_s, 0.8);
  EXPECT_DOUBLE_EQ(phase.at(1), 1.0);
  EXPECT_DOUBLE_EQ(phase.at(4), 0.4);
  EXPECT_DOUBLE_EQ(AmdahlPhase::fit(2.0, 4, 1.25).serial_s, 1.0);  // 1 + 1/4 of 1
}

TEST(AmdahlPhase, ClampsWhatNoSplitExplains) {
  const AmdahlPhase slower = AmdahlPhase::fit(1.0, 2, 1.2);  // more threads, more time: serial
  EXPECT_DOUBLE_EQ(slower.serial_s, 1.0);
  EXPECT_DOUBLE_EQ(slower.parallel_s, 0.0);
  const AmdahlPhase superlinear = AmdahlPhase::fit(1.0, 2, 0.4);  // faster than 1/P: parallel
  EXPECT_DOUBLE_EQ(superlinear.serial_s, 0.0);
  EXPECT_DOUBLE_EQ(superlinear.parallel_s, 1.0);
  EXPECT_DOUBLE_EQ(AmdahlPhase::serial(0.3).at(16), 0.3);
  EXPECT_THROW(AmdahlPhase::fit(1.0, 1, 0.5), std::invalid_argument);
  EXPECT_THROW(AmdahlPhase::fit(0.0, 2, 0.5), std::invalid_argument);
  EXPECT_THROW(AmdahlPhase{}.at(0), std::invalid_argument);
}

// A two-thread time equal to the one-thread time: half the entries passed on cost as much as the
// work that halved. t(P) = 1 / P + 2 (P - 1) / P^2: 1 at 2, 0.25 + 0.375 at 4, 1/16 + 30/256.
TEST(ExchangePhase, FitsTwoPointsAndPassesOnAllButItsOwnShare) {
  const ExchangePhase phase = ExchangePhase::fit(1.0, 2, 1.0);
  EXPECT_DOUBLE_EQ(phase.work_s, 1.0);
  EXPECT_DOUBLE_EQ(phase.exchange_s, 2.0);
  EXPECT_DOUBLE_EQ(phase.at(1), 1.0);
  EXPECT_DOUBLE_EQ(phase.at(2), 1.0);
  EXPECT_DOUBLE_EQ(phase.at(4), 0.625);
  EXPECT_DOUBLE_EQ(phase.at(16), 1.0 / 16 + 30.0 / 256);
  // From 4 threads: 0.5 = 1/4 + x 3/16  =>  x = 4/3.
  EXPECT_DOUBLE_EQ(ExchangePhase::fit(1.0, 4, 0.5).exchange_s, 4.0 / 3);
  // Falling as 1 / P or faster: nothing passed on.
  EXPECT_DOUBLE_EQ(ExchangePhase::fit(1.0, 2, 0.4).exchange_s, 0.0);
  EXPECT_DOUBLE_EQ(ExchangePhase::fit(1.0, 2, 0.4).at(8), 0.125);
  EXPECT_THROW(ExchangePhase::fit(1.0, 1, 0.5), std::invalid_argument);
  EXPECT_THROW(ExchangePhase::fit(1.0, 2, 0.0), std::invalid_argument);
  EXPECT_THROW(ExchangePhase{}.at(0), std::invalid_argument);
}

TEST(AnchoredLoop, ScalesTheReplayToTheMeasuredOneThreadTime) {
  const std::vector<std::uint32_t> trace = fig6_trace();
  const PreparedWork work{WorkView(trace)};
  const Schedule block{ScheduleKind::kStatic, 0};
  // 102 tests measured as 2.04 s: 0.02 s per test.
  const AnchoredLoop loop(work, MachineCosts::tests_only(), block, 2.04);
  EXPECT_DOUBLE_EQ(loop.scale(), 0.02);
  EXPECT_DOUBLE_EQ(loop.seconds(1, block), 2.04);
  // Block over 2 threads: iterations 0-9 hold 4*3 + 3*2 + 3*3 = 27 tests, 10-19 hold 3 + 9*8 = 75.
  EXPECT_DOUBLE_EQ(loop.seconds(2, block), 75 * 0.02);
  // static,1 deals even iterations to thread 0: 3+3+2+2+3+3 + 8*4 = 48 tests; thread 1 holds
  // 3+3+2+3+3 + 8*5 = 54.
  EXPECT_DOUBLE_EQ(loop.seconds(2, {ScheduleKind::kStatic, 1}), 54 * 0.02);
  EXPECT_THROW(AnchoredLoop(work, MachineCosts::tests_only(), block, 0.0), std::invalid_argument);
}

// The replay deals a fixed trace exactly as libgomp does in a real 2-thread loop: each thread's
// share of the trace, from the thread ids a real OpenMP loop records (no timing involved).
TEST(AnchoredLoop, MatchesARealTwoThreadRunOfAFixedTrace) {
  std::vector<std::uint32_t> trace;
  for (std::uint32_t i = 0; i < 997; ++i)
    trace.push_back((i * 7919u) % 61u + (i % 13u == 0 ? 500u : 0u));
  const PreparedWork work{WorkView(trace)};
  for (const Schedule schedule :
       {Schedule{ScheduleKind::kStatic, 0}, Schedule{ScheduleKind::kStatic, 1},
        Schedule{ScheduleKind::kStatic, 64}}) {
    std::vector<int> owner(trace.size(), -1);
    omp_set_schedule(omp_sched_static, schedule.chunk);
#pragma omp parallel for schedule(runtime) num_threads(2)
    for (std::size_t i = 0; i < trace.size(); ++i) owner[i] = omp_get_thread_num();
    std::vector<std::uint64_t> real(2, 0);
    for (std::size_t i = 0; i < trace.size(); ++i)
      real[static_cast<std::size_t>(owner[i])] += trace[i];
    const AnchoredLoop loop(work, MachineCosts::tests_only(), schedule, 1.0);
    const ScheduleOutcome replayed = loop.replay(2, schedule);
    ASSERT_EQ(replayed.threads.size(), 2u);
    for (std::size_t t = 0; t < 2; ++t) {
      EXPECT_EQ(replayed.threads[t].tests, real[t])
          << "chunk " << schedule.chunk << " thread " << t;
      EXPECT_NEAR(replayed.threads[t].seconds, loop.scale() * static_cast<double>(real[t]), 1e-12);
    }
  }
}

TEST(ReplicatedRankWork, DealsBlocksRoundRobin) {
  const std::vector<std::uint32_t> tests{1, 2, 3, 4, 5, 6, 7, 8, 9, 10};
  const std::vector<std::uint32_t> homes(10, 1);
  const std::vector<std::uint8_t> no_builds(10, 0);
  const WorkView view(tests, homes, no_builds);
  const RankWork r0 = replicated_rank_work(view, 2, 3, 0);
  EXPECT_EQ(r0.tests, (std::vector<std::uint32_t>{1, 2, 7, 8}));
  EXPECT_EQ(r0.builds, (std::vector<std::uint8_t>{1, 0, 1, 0}));  // each block starts afresh
  EXPECT_EQ(replicated_rank_work(view, 2, 3, 1).tests, (std::vector<std::uint32_t>{3, 4, 9, 10}));
  EXPECT_EQ(replicated_rank_work(view, 2, 3, 2).tests, (std::vector<std::uint32_t>{5, 6}));
  EXPECT_TRUE(replicated_rank_work(view, 20, 3, 1).tests.empty());  // more ranks than blocks
  EXPECT_THROW(replicated_rank_work(view, 0, 3, 0), std::invalid_argument);
  EXPECT_THROW(replicated_rank_work(view, 2, 3, 3), std::invalid_argument);
}

TEST(CommunicationModel, PricesMessagesAndTrees) {
  const CommunicationModel network{1e-6, 1e9, "test"};
  EXPECT_DOUBLE_EQ(network.message_s(1000), 1e-6 + 1e-6);
  EXPECT_DOUBLE_EQ(network.collective_s(1, 8), 0.0);
  EXPECT_DOUBLE_EQ(network.collective_s(2, 8), network.message_s(8));
  EXPECT_DOUBLE_EQ(network.collective_s(1024, 8), 10 * network.message_s(8));
  EXPECT_DOUBLE_EQ(network.collective_s(1025, 8), 11 * network.message_s(8));
}

TEST(PredictReplicated, TheSlowestRankAndOneReduction) {
  const std::vector<std::uint32_t> trace = fig6_trace();
  const CommunicationModel network{1e-6, 1e9, "test"};
  // Blocks of 10 over 2 ranks: rank 0 holds 27 tests, rank 1 holds 75.
  const MpiPrediction p = predict_replicated(WorkView(trace), MachineCosts::tests_only(), 0.01, 10,
                                             2, 1, {ScheduleKind::kStatic, 0}, network);
  EXPECT_DOUBLE_EQ(p.compute_s, 0.75);
  EXPECT_DOUBLE_EQ(p.communication_s, network.message_s(8));
  EXPECT_EQ(p.slowest_rank, 1);
  EXPECT_DOUBLE_EQ(p.rank_imbalance, (75.0 - 51.0) / 75.0);
  EXPECT_EQ(p.processes(), 2);
  // Hybrid: one rank, 2 threads, static,1 (54 tests on the busier thread), no message.
  const MpiPrediction h = predict_replicated(WorkView(trace), MachineCosts::tests_only(), 0.01, 10,
                                             1, 2, {ScheduleKind::kStatic, 1}, network);
  EXPECT_DOUBLE_EQ(h.compute_s, 0.54);
  EXPECT_DOUBLE_EQ(h.communication_s, 0.0);
  // A fixed cost per rank: paid by every rank, also one with no block (3 ranks, 2 blocks).
  const MpiPrediction f = predict_replicated(WorkView(trace), MachineCosts::tests_only(), 0.01, 10,
                                             3, 1, {ScheduleKind::kStatic, 0}, network, 0.1);
  EXPECT_DOUBLE_EQ(f.compute_s, 0.1 + 0.75);
  EXPECT_DOUBLE_EQ(f.replay_compute_s, f.compute_s);  // no locality factor yet
  const MpiPrediction idle =
      predict_replicated(WorkView(trace), MachineCosts::tests_only(), 0.01, 100, 4, 1,
                         {ScheduleKind::kStatic, 0}, network, 0.1);
  EXPECT_DOUBLE_EQ(idle.compute_s, 0.1 + 1.02);  // one block of all 20 on rank 0, three idle
}

TEST(WithLocality, ScalesTheLoopNotTheFixedCostNorTheMessages) {
  MpiPrediction p;
  p.ranks = 16;
  p.compute_s = 0.1 + 0.4;  // fixed cost 0.1, loop 0.4
  p.communication_s = 1e-5;
  p.slowest_rank = 7;
  const MpiPrediction q = with_locality(p, 1.5, 0.1);
  EXPECT_DOUBLE_EQ(q.compute_s, 0.1 + 0.6);
  EXPECT_DOUBLE_EQ(q.replay_compute_s, 0.5);
  EXPECT_DOUBLE_EQ(q.locality, 1.5);
  EXPECT_DOUBLE_EQ(q.communication_s, 1e-5);
  EXPECT_EQ(q.slowest_rank, 7);
  EXPECT_DOUBLE_EQ(with_locality(p, 1.0, 0.1).compute_s, p.compute_s);
  EXPECT_THROW(with_locality(p, 0.0, 0.1), std::invalid_argument);
}

TEST(PredictDecomposed, WorkShareThenHaloThenCounts) {
  const CommunicationModel network{1e-6, 1e9, "test"};
  const std::vector<DecomposedRank> ranks{{30, 100, 2}, {70, 50, 1}};
  const MpiPrediction p = predict_decomposed(ranks, 100, 1.0, 1, 1.0, 40.0, network);
  EXPECT_DOUBLE_EQ(p.compute_s, 0.7);
  // Rank 1 finishes last: 1 message + 50 * 40 bytes, then 0.7 s; the counts' exchange first.
  const double halo1 = 1e-6 + 50 * 40 / 1e9;
  EXPECT_NEAR(p.communication_s, network.message_s(8.0) + halo1, 1e-15);
  EXPECT_EQ(p.slowest_rank, 1);
  // Two threads at 80% efficiency per rank.
  EXPECT_DOUBLE_EQ(predict_decomposed(ranks, 100, 1.0, 2, 0.8, 40.0, network).compute_s, 0.7 / 1.6);
  // The fixed part is paid whole; the rest is shared by work: 0.2 + 0.8 * 0.7.
  EXPECT_DOUBLE_EQ(predict_decomposed(ranks, 100, 1.0, 1, 1.0, 40.0, network, 0.2).compute_s,
                   0.2 + 0.8 * 0.7);
  EXPECT_THROW(predict_decomposed({}, 100, 1.0, 1, 1.0, 40.0, network), std::invalid_argument);
  EXPECT_THROW(predict_decomposed(ranks, 0, 1.0, 1, 1.0, 40.0, network), std::invalid_argument);
}

TEST(RelativeError, IsSignedOverTheMeasuredValue) {
  EXPECT_NEAR(relative_error(1.1, 1.0), 0.1, 1e-15);
  EXPECT_NEAR(relative_error(0.9, 1.0), -0.1, 1e-15);
}

}  // namespace
}  // namespace contactlab::tuner
