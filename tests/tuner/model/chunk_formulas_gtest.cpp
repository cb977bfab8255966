// The classic chunk-size formulas on inputs worked out by hand.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <numeric>
#include <stdexcept>
#include <string>
#include <vector>

#include "contactlab/tuner_model/chunk_formulas.hpp"

namespace contactlab::tuner {
namespace {

using Sizes = std::vector<std::uint64_t>;

std::uint64_t sum(const Sizes& sizes) {
  return std::accumulate(sizes.begin(), sizes.end(), std::uint64_t{0});
}

TEST(IterationTimeStatistics, PricesEachIterationsTestsHomesAndBuilds) {
  MachineCosts costs;
  costs.seconds_per_test = 2.0;
  costs.seconds_per_iteration = 5.0;
  costs.seconds_per_home = 7.0;
  costs.seconds_per_build = 11.0;
  const std::vector<std::uint32_t> tests{1, 3}, homes{1, 2};
  const std::vector<std::uint8_t> builds{0, 1};
  const IterationTimeStatistics stats =
      iteration_time_statistics(WorkView(tests, homes, builds), costs);
  EXPECT_EQ(stats.iterations, 2u);
  EXPECT_DOUBLE_EQ(stats.mean_tests, 2.0);
  EXPECT_DOUBLE_EQ(stats.stddev_tests, 1.0);  // population: sqrt(((1-2)^2 + (3-2)^2) / 2)
  // Iteration times 5 + 7 + 2 = 14 and 5 + 14 + 11 + 6 = 36.
  EXPECT_DOUBLE_EQ(stats.mean_seconds, 25.0);
  EXPECT_DOUBLE_EQ(stats.stddev_seconds, 11.0);
  EXPECT_EQ(iteration_time_statistics(std::vector<std::uint32_t>{}, costs).iterations, 0u);
}

TEST(KruskalWeiss, MatchesTheFormula) {
  // N = 1000, P = 4, h = sigma = 1 us:
  // (sqrt(2) * 1000 / (4 * sqrt(ln 4)))^(2/3) = (1414.21 / 4.7096)^(2/3) = 300.28^(2/3) = 44.85.
  EXPECT_EQ(kruskal_weiss_chunk(1000, 4, 1e-6, 1e-6), 45);
  // Ten times the overhead: 10^(2/3) = 4.64 times the chunk: 208.2.
  EXPECT_EQ(kruskal_weiss_chunk(1000, 4, 1e-5, 1e-6), 208);
}

TEST(KruskalWeiss, ClampsToOneAndToTheBlock) {
  EXPECT_EQ(kruskal_weiss_chunk(1000, 4, 0.0, 1e-6), 1);      // free chunks: as small as can be
  EXPECT_EQ(kruskal_weiss_chunk(1000, 4, 1e-6, 0.0), 250);    // nothing to balance
  EXPECT_EQ(kruskal_weiss_chunk(1000, 1, 1e-6, 1e-6), 1000);  // ln 1 = 0: one thread
  EXPECT_EQ(kruskal_weiss_chunk(1000, 4, 1.0, 1e-9), 250);    // huge overhead
  EXPECT_THROW(kruskal_weiss_chunk(1000, 0, 1e-6, 1e-6), std::invalid_argument);
  EXPECT_THROW(kruskal_weiss_chunk(1000, 4, -1.0, 1e-6), std::invalid_argument);
}

TEST(KruskalWeiss, FromTheWorkVector) {
  // Work alternating 0 and 2 tests: sigma = 1 test = 1 ns; h = 1 us; N = 1000, P = 4.
  std::vector<std::uint32_t> work;
  for (int i = 0; i < 500; ++i) work.insert(work.end(), {0u, 2u});
  MachineCosts costs;
  costs.seconds_per_test = 1e-9;
  costs.seconds_per_grab = 1e-6;
  // (sqrt(2) * 1000 * 1000 / (4 * sqrt(ln 4)))^(2/3) = 300283^(2/3) = 4485 -> clamped to 250.
  EXPECT_EQ(kruskal_weiss_chunk(work, 4, costs), 250);
  costs.seconds_per_grab = 1e-9;  // h = sigma: 44.85 as above
  EXPECT_EQ(kruskal_weiss_chunk(work, 4, costs), 45);
}

TEST(Factoring, HalvesWhatIsLeftInBatchesOfP) {
  // N = 100, P = 2, x = 2: R = 100 -> 2 x ceil(100/4)=25; R = 50 -> 2 x 13; R = 24 -> 2 x 6;
  // R = 12 -> 2 x 3; R = 6 -> 2 x 2; R = 2 -> 2 x 1.
  const Sizes sizes = factoring_chunk_sequence(100, 2);
  EXPECT_EQ(sizes, (Sizes{25, 25, 13, 13, 6, 6, 3, 3, 2, 2, 1, 1}));
  EXPECT_EQ(factoring_chunk(100, 2), 25);
  // The last batch is cut at the loop's end: N = 10, P = 4: ceil(10/8) = 2, four times would
  // be 8; R = 2 -> ceil(2/8) = 1, twice.
  EXPECT_EQ(factoring_chunk_sequence(10, 4), (Sizes{2, 2, 2, 2, 1, 1}));
  EXPECT_EQ(factoring_chunk_sequence(1, 4), (Sizes{1}));
  EXPECT_TRUE(factoring_chunk_sequence(0, 4).empty());
  EXPECT_THROW(factoring_chunk_sequence(100, 2, 0.5), std::invalid_argument);
  EXPECT_THROW(factoring_chunk(100, 0), std::invalid_argument);
}

TEST(Factoring, StatisticalRuleFromMeanAndSigma) {
  // No variance: x = 1, one batch of P chunks of R / P.
  EXPECT_EQ(factoring_chunk_sequence(100, 2, 1.0, 0.0), (Sizes{50, 50}));
  // N = 400, P = 4, mu = sigma = 1: b = 4 / (2 * 20) = 0.1, x = 1 + 0.01 + 0.1 * sqrt(2.01)
  // = 1.15177; chunk = ceil(400 / 4.6071) = ceil(86.82) = 87.
  const Sizes sizes = factoring_chunk_sequence(400, 4, 1.0, 1.0);
  ASSERT_GE(sizes.size(), 4u);
  EXPECT_EQ(sizes[0], 87u);
  EXPECT_EQ(sizes[3], 87u);
  EXPECT_EQ(sum(sizes), 400u);
  EXPECT_THROW(factoring_chunk_sequence(100, 2, 0.0, 1.0), std::invalid_argument);
}

TEST(GuidedSelfScheduling, TakesRemainingOverP) {
  EXPECT_EQ(guided_self_scheduling_chunk(100, 4), 25);
  EXPECT_EQ(guided_self_scheduling_chunk(101, 4), 26);
  EXPECT_EQ(guided_self_scheduling_chunk(0, 4), 1);
}

TEST(TrivialChunks, BlockAndEighthBlock) {
  EXPECT_EQ(block_chunk(1000, 4), 250);
  EXPECT_EQ(block_chunk(1001, 4), 251);
  EXPECT_EQ(eighth_block_chunk(1000, 4), 32);  // ceil(1000 / 32) = 31.25 -> 32
  EXPECT_EQ(eighth_block_chunk(3, 4), 1);
  EXPECT_THROW(block_chunk(10, 0), std::invalid_argument);
}

TEST(ClassicChunks, ListsEveryFormula) {
  const std::vector<std::uint32_t> work(1000, 3);
  const std::vector<NamedChunk> chunks = classic_chunks(work, 4, MachineCosts{});
  ASSERT_EQ(chunks.size(), 5u);
  EXPECT_EQ(chunks[0].name, "kruskal_weiss");
  EXPECT_EQ(chunks[0].chunk, 250);  // no variance
  EXPECT_EQ(chunks[1].name, "factoring");
  EXPECT_EQ(chunks[1].chunk, 125);
  EXPECT_EQ(chunks[2].name, "guided_self_scheduling");
  EXPECT_EQ(chunks[2].chunk, 250);
  EXPECT_EQ(chunks[3].name, "block");
  EXPECT_EQ(chunks[4].name, "eighth_block");
  EXPECT_EQ(chunks[4].chunk, 32);
  EXPECT_NE(chunks[0].inputs.find("N=1000,P=4"), std::string::npos) << chunks[0].inputs;
}

TEST(ClassicChunks, FactoringSequenceRunsInTheSimulator) {
  std::vector<std::uint32_t> work(300, 1);
  work.insert(work.end(), 100, 50);
  const Sizes sizes = factoring_chunk_sequence(work.size(), 4);
  const ScheduleOutcome outcome = simulate_chunk_sequence(work, 4, sizes);
  EXPECT_EQ(outcome.total_chunks, sizes.size());
  std::uint64_t tests = 0;
  for (const ThreadShare& share : outcome.threads) tests += share.tests;
  EXPECT_EQ(tests, 300u + 100u * 50u);
  // Factoring balances the dense tail far better than the block partition.
  EXPECT_LT(outcome.test_imbalance,
            simulate_schedule(work, 4, {ScheduleKind::kStatic, 0}).test_imbalance);
}

}  // namespace
}  // namespace contactlab::tuner
