// count_then_fill: a filter and an expansion give the one-thread loop's output, in its order, for
// any team size, with the outputs sized once.
#include <gtest/gtest.h>

#include <cstddef>
#include <cstdint>
#include <vector>

#include "contactlab/kernels/count_then_fill.hpp"

namespace contactlab {
namespace {

// Input k gives k % 4 outputs (none for multiples of 4): 10 k + 0, 10 k + 1, ...
std::vector<std::uint64_t> expand(std::size_t n, int threads, int* size_calls) {
  std::vector<std::uint64_t> out;
  count_then_fill(
      n, threads,
      [](std::size_t first, std::size_t last) {
        std::size_t c = 0;
        for (std::size_t k = first; k < last; ++k) c += k % 4;
        return c;
      },
      [&](std::size_t total) {
        ++*size_calls;
        out.assign(total, UINT64_MAX);
      },
      [&](std::size_t first, std::size_t last, std::size_t at) {
        for (std::size_t k = first; k < last; ++k) {
          for (std::size_t j = 0; j < k % 4; ++j) out[at++] = 10 * k + j;
        }
      });
  return out;
}

TEST(CountThenFill, GivesTheOneThreadLoopsOutputForAnyTeam) {
  for (const std::size_t n : {std::size_t{0}, std::size_t{1}, std::size_t{5}, std::size_t{1001}}) {
    std::vector<std::uint64_t> expected;
    for (std::size_t k = 0; k < n; ++k) {
      for (std::size_t j = 0; j < k % 4; ++j) expected.push_back(10 * k + j);
    }
    for (const int threads : {1, 2, 3, 4, 8, 16}) {
      int size_calls = 0;
      EXPECT_EQ(expand(n, threads, &size_calls), expected) << n << " " << threads;
      EXPECT_EQ(size_calls, 1);
    }
  }
}

}  // namespace
}  // namespace contactlab
