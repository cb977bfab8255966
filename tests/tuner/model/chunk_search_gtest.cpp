// The chunk search on synthetic noisy cost functions of log2 k with
// a fixed-seed generator: it finds the known optimum with far fewer evaluations than the
// exhaustive sweep, prefers the larger chunk among ties, and honours its budget.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <functional>
#include <stdexcept>
#include <thread>
#include <vector>

#include "contactlab/kernels/rng.hpp"
#include "contactlab/tuner_model/chunk_search.hpp"

namespace contactlab::tuner {
namespace {

// Gaussian-like noise from a fixed-seed generator: the sum of 12 uniforms minus 6 has mean 0
// and variance 1 (Irwin-Hall).
class Noise {
 public:
  explicit Noise(std::uint64_t seed) : rng_(seed) {}
  double next() {
    double sum = 0.0;
    for (int i = 0; i < 12; ++i) sum += static_cast<double>(rng_.next() >> 11) * 0x1.0p-53;
    return sum - 6.0;
  }

 private:
  Xoshiro256 rng_;
};

// A measured loop whose true time is `seconds(log2 k)`, with 1% multiplicative noise; nine
// samples per call. Counts the calls.
struct SyntheticLoop {
  std::function<double(double)> seconds;
  Noise noise{20240611};
  int calls = 0;
  double relative_noise = 0.01;

  MeasureChunk measure() {
    return [this](int chunk) {
      ++calls;
      std::vector<double> samples;
      samples.reserve(9);
      const double truth = seconds(std::log2(static_cast<double>(chunk)));
      for (int i = 0; i < 9; ++i) samples.push_back(truth * (1.0 + relative_noise * noise.next()));
      return samples;
    };
  }
};

// Convex in log2 k with the optimum at k = 256; neighbours on the grid are 5% slower.
double convex(double log2_chunk) {
  return 1e-3 * (1.0 + 0.05 * (log2_chunk - 8) * (log2_chunk - 8));
}

// Flat from k = 256 to k = 4096, rising on both sides.
double plateau(double log2_chunk) {
  const double below = std::max(0.0, 8.0 - log2_chunk), above = std::max(0.0, log2_chunk - 12.0);
  return 1e-3 * (1.0 + 0.05 * (below * below + above * above));
}

TEST(SearchChunk, FindsTheOptimumFromTheModelSeedWithFewEvaluations) {
  SyntheticLoop loop{convex};
  ChunkSearchOptions options;
  options.seed_chunk = 64;  // a model off by two grid steps
  const ChunkSearchResult search = search_chunk(loop.measure(), options);
  EXPECT_EQ(search.chosen_chunk, 256);
  EXPECT_EQ(search.fastest_chunk, 256);
  EXPECT_EQ(search.evaluations, loop.calls);
  EXPECT_EQ(search.stop, SearchStop::kConverged);

  SyntheticLoop sweep_loop{convex};
  const ChunkSearchResult exhaustive = exhaustive_chunk_sweep(sweep_loop.measure(), options);
  EXPECT_EQ(exhaustive.evaluations, 17);
  EXPECT_EQ(exhaustive.chosen_chunk, 256);
  // Seed 64, neighbours 32 and 128, then 512 and 256; at most 8 of 17 whichever way the noise
  // tips the near-tie between 128 and 512.
  EXPECT_LE(search.evaluations, 8);
  EXPECT_DOUBLE_EQ(regret(exhaustive, search.chosen_chunk), 0.0);
  EXPECT_EQ(search.measured.front().samples_seconds.size(), 9u);
  EXPECT_GT(search.sampled_seconds, 0.0);
  EXPECT_GE(search.measuring_seconds, 0.0);
}

TEST(SearchChunk, FindsTheOptimumFromEitherEdgeOfTheGrid) {
  for (const int seed : {1, 65536}) {
    SyntheticLoop loop{convex};
    ChunkSearchOptions options;
    options.seed_chunk = seed;
    const ChunkSearchResult search = search_chunk(loop.measure(), options);
    EXPECT_EQ(search.chosen_chunk, 256) << "seed " << seed;
    EXPECT_LT(search.evaluations, 17) << "seed " << seed;
  }
}

TEST(SearchChunk, PrefersTheLargestChunkAmongTies) {
  SyntheticLoop loop{plateau};
  ChunkSearchOptions options;
  options.seed_chunk = 256;
  const ChunkSearchResult search = search_chunk(loop.measure(), options);
  // Every chunk from 256 to 4096 is as fast within the noise: the largest wins.
  EXPECT_EQ(search.chosen_chunk, 4096);
  EXPECT_GE(search.fastest_chunk, 256);
  EXPECT_LE(search.fastest_chunk, 4096);
  SyntheticLoop sweep_loop{plateau};
  const ChunkSearchResult exhaustive = exhaustive_chunk_sweep(sweep_loop.measure(), options);
  EXPECT_EQ(exhaustive.chosen_chunk, 4096);
  EXPECT_LT(search.evaluations, exhaustive.evaluations);
  EXPECT_LT(std::abs(regret(exhaustive, search.chosen_chunk)), 0.02);
}

TEST(SearchChunk, NoisyOverlapAloneDoesNotPickASlowerLargerChunk) {
  // 30% spread and three samples a call: every interval overlaps every other. The rising side
  // above k = 256 is 5%, 20%, ... slower; the equivalence margin (2%) keeps the search from
  // taking the largest overlapping chunk, as the overlap test alone would.
  MeasureChunk wide = [&](int chunk) {
    const double truth = convex(std::log2(static_cast<double>(chunk)));
    return std::vector<double>{0.7 * truth, truth, 1.3 * truth};
  };
  ChunkSearchOptions options;
  options.seed_chunk = 256;
  EXPECT_EQ(search_chunk(wide, options).chosen_chunk, 256);
  options.equivalence_margin = 0.06;  // a looser margin admits the 5% slower neighbour
  EXPECT_EQ(search_chunk(wide, options).chosen_chunk, 512);
}

TEST(ExhaustiveSweep, RoundsVisitEveryChunkOncePerRoundInShuffledOrder) {
  std::vector<int> visits;
  MeasureChunk record = [&](int chunk) {
    visits.push_back(chunk);
    return std::vector<double>{convex(std::log2(static_cast<double>(chunk)))};
  };
  ChunkSearchOptions options;
  options.rounds = 3;
  const ChunkSearchResult all = exhaustive_chunk_sweep(record, options);
  ASSERT_EQ(visits.size(), 3u * 17u);
  EXPECT_EQ(all.evaluations, 51);
  for (std::ptrdiff_t round = 0; round < 3; ++round) {
    std::vector<int> this_round(visits.begin() + 17 * round, visits.begin() + 17 * (round + 1));
    EXPECT_FALSE(std::is_sorted(this_round.begin(), this_round.end())) << "round " << round;
    std::sort(this_round.begin(), this_round.end());
    EXPECT_EQ(this_round, options.grid) << "round " << round;
  }
  EXPECT_EQ(all.at(256).samples_seconds.size(), 3u);
  EXPECT_EQ(all.fastest_chunk, 256);
  options.rounds = 0;
  EXPECT_THROW(exhaustive_chunk_sweep(record, options), std::invalid_argument);
}

// The block (chunk 0: one share per thread) is measured in every round with the grid, as the
// largest chunk: it wins where it is fastest, and ties with a chunk in its favour.
TEST(ExhaustiveSweep, MeasuresTheBlockWithTheGridAsTheLargestChunk) {
  auto sweep = [](double block_seconds) {
    std::vector<int> visits;
    MeasureChunk record = [&visits, block_seconds](int chunk) {
      visits.push_back(chunk);
      const double t = chunk == 0 ? block_seconds : convex(std::log2(static_cast<double>(chunk)));
      return std::vector<double>{t, t, t};
    };
    ChunkSearchOptions options;
    options.rounds = 2;
    options.with_block = true;
    ChunkSearchResult all = exhaustive_chunk_sweep(record, options);
    EXPECT_EQ(std::count(visits.begin(), visits.end(), 0), 2);
    EXPECT_EQ(visits.size(), 2u * 18u);
    EXPECT_EQ(all.measured.back().chunk, 0);
    EXPECT_EQ(all.measured.back().evaluations, 2);
    return all;
  };
  const ChunkSearchResult faster = sweep(0.9e-3);  // 10 % below the grid's best
  EXPECT_EQ(faster.fastest_chunk, 0);
  EXPECT_EQ(faster.chosen_chunk, 0);
  EXPECT_NEAR(regret(faster, 256), 1.0 / 0.9 - 1.0, 1e-12);
  const ChunkSearchResult slower = sweep(2e-3);
  EXPECT_EQ(slower.fastest_chunk, 256);
  EXPECT_EQ(slower.chosen_chunk, 256);
  const ChunkSearchResult tied = sweep(1e-3);  // equal to k = 256: the larger chunk wins
  EXPECT_EQ(tied.fastest_chunk, 0);

  ChunkSearchOptions options;
  options.with_block = true;
  SyntheticLoop loop{convex};
  EXPECT_THROW(search_chunk(loop.measure(), options), std::invalid_argument);
}

TEST(SearchChunk, ConfirmationRoundsAddSamplesToTheContenders) {
  SyntheticLoop loop{plateau};
  ChunkSearchOptions options;
  options.seed_chunk = 256;
  options.confirmation_rounds = 1;
  const ChunkSearchResult search = search_chunk(loop.measure(), options);
  EXPECT_EQ(search.chosen_chunk, 4096);
  EXPECT_EQ(search.at(4096).evaluations, 2);
  EXPECT_EQ(search.at(4096).samples_seconds.size(), 18u);
  EXPECT_THROW(search.at(3), std::invalid_argument);
}

TEST(SearchChunk, StopsAtTheEvaluationBudget) {
  SyntheticLoop loop{convex};
  ChunkSearchOptions options;
  options.seed_chunk = 1;
  options.budget.max_evaluations = 3;
  const ChunkSearchResult search = search_chunk(loop.measure(), options);
  EXPECT_EQ(search.evaluations, 3);
  EXPECT_EQ(loop.calls, 3);
  EXPECT_EQ(search.stop, SearchStop::kEvaluationBudget);
  EXPECT_EQ(search.measured.size(), 3u);
  EXPECT_NO_THROW(search.at(search.chosen_chunk));
}

TEST(SearchChunk, StopsAtTheTimeBudget) {
  int calls = 0;
  const MeasureChunk slow = [&calls](int chunk) {
    ++calls;
    std::this_thread::sleep_for(std::chrono::milliseconds(3));
    return std::vector<double>(6, convex(std::log2(static_cast<double>(chunk))));
  };
  ChunkSearchOptions options;
  options.seed_chunk = 1;
  options.budget.max_measure_seconds = 0.005;  // two calls of at least 3 ms use it up
  const ChunkSearchResult search = search_chunk(slow, options);
  EXPECT_EQ(search.stop, SearchStop::kTimeBudget);
  EXPECT_LE(search.evaluations, 2);
  EXPECT_GE(search.evaluations, 1);
  EXPECT_GE(search.measuring_seconds, 0.005);
}

TEST(SearchChunk, SeededByTheScheduleModel) {
  // The "machine" is the schedule model itself plus noise; its own prediction as the seed
  // lands on the optimum at once.
  std::vector<std::uint32_t> work(4000, 2);
  work.insert(work.end(), 1000, 60);
  MachineCosts costs;
  const int threads = 4;
  const ChunkPrediction prediction =
      predict_best_chunk(work, threads, ScheduleKind::kStatic, costs, log2_chunk_grid());
  Noise noise(7);
  const MeasureChunk measure = [&](int chunk) {
    const double truth =
        simulate_schedule(work, threads, {ScheduleKind::kStatic, chunk}, costs).makespan_seconds;
    std::vector<double> samples;
    samples.reserve(9);
    for (int i = 0; i < 9; ++i) samples.push_back(truth * (1.0 + 0.002 * noise.next()));
    return samples;
  };
  ChunkSearchOptions options;
  options.seed_chunk = prediction.best_chunk;
  const ChunkSearchResult search = search_chunk(measure, options);
  const ChunkSearchResult exhaustive = exhaustive_chunk_sweep(measure, options);
  EXPECT_LE(search.evaluations, 5);
  EXPECT_LT(regret(exhaustive, search.chosen_chunk), 0.01);
  EXPECT_GE(search.chosen_chunk, prediction.best_chunk);
}

TEST(SearchChunk, HandlesGridsOfOneAndTwoChunks) {
  SyntheticLoop loop{convex};
  ChunkSearchOptions options;
  options.grid = {64};
  const ChunkSearchResult one = search_chunk(loop.measure(), options);
  EXPECT_EQ(one.chosen_chunk, 64);
  EXPECT_EQ(one.evaluations, 1);
  options.grid = {128, 256};
  options.seed_chunk = 1;  // nearest grid point: 128
  const ChunkSearchResult two = search_chunk(loop.measure(), options);
  EXPECT_EQ(two.chosen_chunk, 256);
  EXPECT_EQ(two.evaluations, 2);
}

TEST(SearchChunk, RejectsBadOptionsAndSamples) {
  SyntheticLoop loop{convex};
  ChunkSearchOptions options;
  options.grid = {1, 4, 2};
  EXPECT_THROW(search_chunk(loop.measure(), options), std::invalid_argument);
  options.grid = {};
  EXPECT_THROW(exhaustive_chunk_sweep(loop.measure(), options), std::invalid_argument);
  options = {};
  options.budget.max_evaluations = 0;
  EXPECT_THROW(search_chunk(loop.measure(), options), std::invalid_argument);
  options = {};
  const MeasureChunk nothing = [](int) { return std::vector<double>{}; };
  try {
    search_chunk(nothing, options);
    FAIL() << "no exception";
  } catch (const std::invalid_argument& error) {
    EXPECT_EQ(std::string(error.what()).rfind("search_chunk: measure(", 0), 0u) << error.what();
  }
  const MeasureChunk not_a_number = [](int) { return std::vector<double>{std::nan("")}; };
  EXPECT_THROW(search_chunk(not_a_number, options), std::invalid_argument);
}

TEST(Regret, IsTheRelativeExcessOverTheBest) {
  EXPECT_NEAR(regret(1.1, 1.0), 0.1, 1e-12);
  EXPECT_DOUBLE_EQ(regret(2.0, 2.0), 0.0);
  EXPECT_THROW(regret(1.0, 0.0), std::invalid_argument);
  SyntheticLoop loop{convex};
  const ChunkSearchResult exhaustive = exhaustive_chunk_sweep(loop.measure(), ChunkSearchOptions{});
  // k = 1024 is two grid steps from the optimum: 1 + 0.05 * 4 = 20% slower, within the noise.
  EXPECT_NEAR(regret(exhaustive, 1024), 0.2, 0.03);
  EXPECT_THROW(regret(exhaustive, 3), std::invalid_argument);
}

}  // namespace
}  // namespace contactlab::tuner
