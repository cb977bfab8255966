// The output term on hand-computed cases: the small point's cost at and below it, the large
// point's at and past it, log-linear in between, split over threads, the point of the right
// thread count, and nothing from nothing.
#include <gtest/gtest.h>

#include <vector>

#include "contactlab/tuner_model/output_cost.hpp"

namespace contactlab::tuner {
namespace {

// 1 ns per entry at 4 MB, 5 ns at 400 MB, at one thread; at two threads 1.5 and 4 per thread.
const std::vector<OutputCost> kCosts{{1, 4e6, 1e-9, 4e8, 5e-9}, {2, 4e6, 1.5e-9, 4e8, 4e-9}};

TEST(OutputCost, TheSmallPointAtAndBelowIt) {
  EXPECT_DOUBLE_EQ(output_seconds(kCosts, 1'000'000, 1), 1e6 * 1e-9);  // exactly 4 MB
  EXPECT_DOUBLE_EQ(output_seconds(kCosts, 1'000, 1), 1e3 * 1e-9);
}

TEST(OutputCost, NothingFromNothing) {
  EXPECT_EQ(output_seconds(kCosts, 0, 1), 0.0);
  EXPECT_EQ(output_seconds({}, 1'000'000'000, 1), 0.0);
  // A calibration output with no contacts (0 bytes) is not a point to interpolate from.
  const std::vector<OutputCost> empty_small{{1, 0.0, 0.0, 4e8, 5e-9}};
  EXPECT_EQ(output_seconds(empty_small, 10'000'000, 1), 0.0);
  EXPECT_DOUBLE_EQ(output_seconds(empty_small, 100'000'000, 1), 1e8 * 5e-9);
}

TEST(OutputCost, TheLargePointAtAndPastIt) {
  EXPECT_DOUBLE_EQ(output_seconds(kCosts, 100'000'000, 1), 1e8 * 5e-9);
  EXPECT_DOUBLE_EQ(output_seconds(kCosts, 300'000'000, 1), 3e8 * 5e-9);  // held constant
}

TEST(OutputCost, LogLinearInBetween) {
  // 40 MB is half way from 4 MB to 400 MB in log(bytes): 3 ns per entry.
  EXPECT_NEAR(output_seconds(kCosts, 10'000'000, 1), 1e7 * 3e-9, 1e-12);
}

TEST(OutputCost, ThePointOfTheThreadCountAndTheEntriesSplitOverThreads) {
  // 2 threads: 4 ns per entry per thread, half the entries each.
  EXPECT_DOUBLE_EQ(output_seconds(kCosts, 100'000'000, 2), 5e7 * 4e-9);
  // 16 threads: the 2-thread point, 1/16 of the entries each (predicted, perfect scaling).
  EXPECT_DOUBLE_EQ(output_seconds(kCosts, 160'000'000, 16), 1e7 * 4e-9);
  // Below every calibrated count (only a 2-thread point): that point.
  const std::vector<OutputCost> two{kCosts[1]};
  EXPECT_DOUBLE_EQ(output_seconds(two, 100'000'000, 1), 1e8 * 4e-9);
}

}  // namespace
}  // namespace contactlab::tuner
