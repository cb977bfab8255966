// The output term on hand-computed cases: the low point's cost at and below its degree, the
// high point's at and past it, log-linear in between, split over threads, the point of the
// right thread count, and nothing from nothing.
#include <gtest/gtest.h>

#include <vector>

#include "contactlab/tuner_model/output_cost.hpp"

namespace contactlab::tuner {
namespace {

// 1 ns per entry at degree 100, 5 ns at 10,000, at one thread; at two threads 1.5 and 4.
const std::vector<OutputCost> kCosts{{1, 100, 1e-9, 10'000, 5e-9}, {2, 100, 1.5e-9, 10'000, 4e-9}};

TEST(OutputCost, TheLowPointAtAndBelowItsDegree) {
  EXPECT_DOUBLE_EQ(output_seconds(kCosts, {1'000'000, 100}, 1), 1e6 * 1e-9);
  EXPECT_DOUBLE_EQ(output_seconds(kCosts, {1'000'000, 3}, 1), 1e6 * 1e-9);
}

TEST(OutputCost, NothingFromNothing) {
  EXPECT_EQ(output_seconds(kCosts, {0, 500}, 1), 0.0);
  EXPECT_EQ(output_seconds({}, {1'000'000'000, 500}, 1), 0.0);
  // A calibration scene without contacts (degree 0) is not a point to interpolate from.
  const std::vector<OutputCost> empty_low{{1, 0.0, 0.0, 10'000, 5e-9}};
  EXPECT_EQ(output_seconds(empty_low, {10'000'000, 1'000}, 1), 0.0);
  EXPECT_DOUBLE_EQ(output_seconds(empty_low, {10'000'000, 20'000}, 1), 1e7 * 5e-9);
}

TEST(OutputCost, TheHighPointAtAndPastItsDegree) {
  EXPECT_DOUBLE_EQ(output_seconds(kCosts, {100'000'000, 10'000}, 1), 1e8 * 5e-9);
  EXPECT_DOUBLE_EQ(output_seconds(kCosts, {100'000'000, 1e6}, 1), 1e8 * 5e-9);  // held constant
}

TEST(OutputCost, LogLinearInBetween) {
  // Degree 1,000 is half way from 100 to 10,000 in log(degree): 3 ns per entry.
  EXPECT_NEAR(output_seconds(kCosts, {10'000'000, 1'000}, 1), 1e7 * 3e-9, 1e-12);
}

TEST(OutputCost, ThePointOfTheThreadCountAndTheEntriesSplitOverThreads) {
  // 2 threads: 4 ns per entry per thread, half the entries each.
  EXPECT_DOUBLE_EQ(output_seconds(kCosts, {100'000'000, 10'000}, 2), 5e7 * 4e-9);
  // 16 threads: the 2-thread point, 1/16 of the entries each (predicted, perfect scaling).
  EXPECT_DOUBLE_EQ(output_seconds(kCosts, {160'000'000, 10'000}, 16), 1e7 * 4e-9);
  // Below every calibrated count (only a 2-thread point): that point.
  const std::vector<OutputCost> two{kCosts[1]};
  EXPECT_DOUBLE_EQ(output_seconds(two, {100'000'000, 10'000}, 1), 1e8 * 4e-9);
}

// The half stencil's reverse entries passed on: 1 + exchange (P - 1) / P with the exchange of the
// thread count's point; an exchange fitted from a passing deal's assembly against the block's.
TEST(OutputCost, PassingEntriesOnCostsTheExchangeOfThePassedShare) {
  std::vector<OutputCost> costs = kCosts;
  costs[1].exchange = 2.0;
  EXPECT_DOUBLE_EQ(exchange_factor(costs, 1), 1.0);
  EXPECT_DOUBLE_EQ(exchange_factor(costs, 2), 2.0);  // half of them, twice a write each
  EXPECT_DOUBLE_EQ(exchange_factor(costs, 16), 1.0 + 2.0 * 15 / 16);
  EXPECT_DOUBLE_EQ(exchange_factor(kCosts, 16), 1.0);  // not measured: none
  EXPECT_DOUBLE_EQ(exchange_factor({}, 16), 1.0);
  // Two threads: the passing deal's assembly twice the block's = 1 + e / 2, so e = 2.
  EXPECT_DOUBLE_EQ(fit_exchange(0.2, 0.1, 2), 2.0);
  // Four: 1.5 = 1 + e 3 / 4, so e = 2 / 3.
  EXPECT_DOUBLE_EQ(fit_exchange(0.15, 0.1, 4), 2.0 / 3);
  EXPECT_EQ(fit_exchange(0.09, 0.1, 2), 0.0);  // no slower: nothing
  EXPECT_EQ(fit_exchange(0.2, 0.1, 1), 0.0);
  EXPECT_EQ(fit_exchange(0.2, 0.0, 2), 0.0);
}

}  // namespace
}  // namespace contactlab::tuner
