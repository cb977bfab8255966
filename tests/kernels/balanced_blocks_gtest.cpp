// BalancedBlocks: one consecutive block per thread, in thread order, tiling the iterations, each
// starting at the first iteration whose prefix of weights reaches t / P of the total (checked
// against that definition computed serially, and on hand-computed weights).
#include <gtest/gtest.h>
#include <omp.h>

#include <cstdint>
#include <string>
#include <vector>

#include "contactlab/kernels/balanced_blocks.hpp"

namespace contactlab {
namespace {

std::vector<IterationBlock> blocks_of(const std::vector<std::uint64_t>& weights, int threads) {
  BalancedBlocks balanced;
  balanced.prepare(threads);
  std::vector<IterationBlock> blocks(threads);
#pragma omp parallel num_threads(threads)
  {
    blocks[omp_get_thread_num()] =
        balanced.block(weights.size(), [&](std::uint64_t k) { return weights[k]; });
  }
  return blocks;
}

// The definition: block t begins at the smallest k with prefix(k) >= total t / P.
std::vector<std::uint64_t> reference_starts(const std::vector<std::uint64_t>& weights, int p) {
  std::uint64_t total = 0;
  for (const std::uint64_t w : weights) total += w;
  std::vector<std::uint64_t> starts;
  for (int t = 0; t < p; ++t) {
    const std::uint64_t target = total / p * t + total % p * t / p;
    std::uint64_t prefix = 0, k = 0;
    while (prefix < target) prefix += weights[k++];
    starts.push_back(k);
  }
  return starts;
}

TEST(BalancedBlocks, HandComputedWeights) {
  // Total 18: at two threads the second block starts where the prefix reaches 9 (after 5).
  const std::vector<std::uint64_t> weights = {5, 1, 1, 1, 1, 1, 1, 1, 1, 5};
  const auto two = blocks_of(weights, 2);
  EXPECT_EQ(two[0].begin, 0u);
  EXPECT_EQ(two[0].end, 5u);
  EXPECT_EQ(two[1].begin, 5u);
  EXPECT_EQ(two[1].end, 10u);
  // Three threads: targets 6 and 12, reached after iterations 2 and 8.
  const auto three = blocks_of(weights, 3);
  EXPECT_EQ(three[0].end, 2u);
  EXPECT_EQ(three[1].end, 8u);
  EXPECT_EQ(three[2].end, 10u);
  // One heavy iteration takes a block to itself; the threads after it share the rest.
  const auto heavy = blocks_of({100, 1, 1, 1, 1}, 4);
  EXPECT_EQ(heavy[0].end, 1u);
  EXPECT_EQ(heavy[3].end, 5u);
}

TEST(BalancedBlocks, TileTheIterationsAsTheDefinitionSaysAtAnyTeamSize) {
  std::vector<std::uint64_t> weights;
  std::uint64_t state = 12345;
  for (int k = 0; k < 1000; ++k) {
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    // Heavy-tailed, like a clustered scene's homes: most light, a few a hundred times heavier.
    weights.push_back(1 + ((state >> 33) % 100 == 0 ? 500 : (state >> 40) % 8));
  }
  for (const std::size_t m : {std::size_t{0}, std::size_t{1}, std::size_t{3}, weights.size()}) {
    const std::vector<std::uint64_t> w(weights.begin(), weights.begin() + m);
    for (const int p : {1, 2, 3, 5, 8, 16, 33}) {
      SCOPED_TRACE("m = " + std::to_string(m) + ", threads = " + std::to_string(p));
      const auto blocks = blocks_of(w, p);
      const auto starts = reference_starts(w, p);
      std::uint64_t next = 0;
      for (int t = 0; t < p; ++t) {
        EXPECT_EQ(blocks[t].begin, next);
        EXPECT_EQ(blocks[t].begin, starts[t]);
        EXPECT_LE(blocks[t].begin, blocks[t].end);
        next = blocks[t].end;
      }
      EXPECT_EQ(next, m);
    }
  }
}

}  // namespace
}  // namespace contactlab
