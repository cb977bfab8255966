// Statistics with known answers: medians, the order-statistic interval of the median, load
// imbalance, and the repetition driver (fixed, adaptive, budget, maximum).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <vector>

#include "contactlab/kernels/error.hpp"
#include "contactlab/support/statistics.hpp"

namespace contactlab {
namespace {

std::vector<double> one_to(int n) {
  std::vector<double> v(n);
  std::iota(v.begin(), v.end(), 1.0);
  return v;
}

TEST(Median, OddCountIsTheMiddleValue) {
  EXPECT_EQ(median(std::vector<double>{3.0, 1.0, 2.0}), 2.0);
  EXPECT_EQ(median(std::vector<double>{7.0}), 7.0);
  EXPECT_EQ(median(std::vector<double>{5.0, 1.0, 4.0, 2.0, 3.0}), 3.0);
}

TEST(Median, EvenCountIsTheMeanOfTheTwoMiddleValues) {
  EXPECT_EQ(median(std::vector<double>{4.0, 1.0, 3.0, 2.0}), 2.5);
  EXPECT_EQ(median(std::vector<double>{1.0, 2.0}), 1.5);
  EXPECT_EQ(median(std::vector<double>{2.0, 2.0, 2.0, 9.0}), 2.0);
}

TEST(Median, RejectsEmptyAndNaN) {
  EXPECT_THROW(median(std::vector<double>{}), InputError);
  EXPECT_THROW(median(std::vector<double>{1.0, std::nan("")}), InputError);
}

TEST(OrderStatisticCoverage, KnownBinomialValues) {
  // k = 1: 1 - 2 / 2^n.
  EXPECT_DOUBLE_EQ(order_statistic_coverage(5, 1), 1.0 - 2.0 / 32.0);
  EXPECT_DOUBLE_EQ(order_statistic_coverage(6, 1), 1.0 - 2.0 / 64.0);
  // n = 10, k = 2: 1 - 2 (1 + 10) / 1024.
  EXPECT_NEAR(order_statistic_coverage(10, 2), 1.0 - 22.0 / 1024.0, 1e-12);
  // n = 20, k = 6: 1 - 2 (1 + 20 + 190 + 1140 + 4845 + 15504) / 2^20.
  EXPECT_NEAR(order_statistic_coverage(20, 6), 1.0 - 2.0 * 21700.0 / 1048576.0, 1e-12);
  EXPECT_THROW(order_statistic_coverage(5, 0), InputError);
  EXPECT_THROW(order_statistic_coverage(5, 4), InputError);
}

TEST(MedianInterval, TwentySamplesGiveTheSixthAndFifteenth) {
  // The classic table value: for n = 20 the 95% interval is [x_(6), x_(15)].
  std::vector<double> v = one_to(20);
  std::reverse(v.begin(), v.end());  // input order must not matter
  const MedianInterval i = median_interval(v, 0.95);
  EXPECT_EQ(i.lower_rank, 6u);
  EXPECT_EQ(i.upper_rank, 15u);
  EXPECT_EQ(i.low, 6.0);
  EXPECT_EQ(i.high, 15.0);
  EXPECT_TRUE(i.reached_level);
  EXPECT_NEAR(i.coverage, 0.958611, 1e-6);
}

TEST(MedianInterval, TenSamplesGiveTheSecondAndNinth) {
  const MedianInterval i = median_interval(one_to(10), 0.95);
  EXPECT_EQ(i.low, 2.0);
  EXPECT_EQ(i.high, 9.0);
  EXPECT_NEAR(i.coverage, 0.978515625, 1e-12);
  // k = 3 covers 0.890625: enough for 89%.
  EXPECT_EQ(median_interval(one_to(10), 0.89).lower_rank, 3u);
}

TEST(MedianInterval, SixIsTheSmallestCountReaching95Percent) {
  const MedianInterval six = median_interval(one_to(6), 0.95);
  EXPECT_TRUE(six.reached_level);
  EXPECT_EQ(six.low, 1.0);
  EXPECT_EQ(six.high, 6.0);
  const MedianInterval five = median_interval(one_to(5), 0.95);
  EXPECT_FALSE(five.reached_level);
  EXPECT_EQ(five.low, 1.0);
  EXPECT_EQ(five.high, 5.0);
  EXPECT_DOUBLE_EQ(five.coverage, 0.9375);
}

TEST(MedianInterval, DegenerateSamples) {
  const MedianInterval single = median_interval(std::vector<double>{3.5}, 0.95);
  EXPECT_EQ(single.low, 3.5);
  EXPECT_EQ(single.high, 3.5);
  EXPECT_EQ(single.coverage, 0.0);
  EXPECT_FALSE(single.reached_level);

  const Summary constant = summarize(std::vector<double>(8, 2.0));
  EXPECT_EQ(constant.median, 2.0);
  EXPECT_EQ(constant.interval.low, 2.0);
  EXPECT_EQ(constant.interval.high, 2.0);
  EXPECT_EQ(constant.relative_half_width, 0.0);

  const Summary zeros = summarize(std::vector<double>(8, 0.0));
  EXPECT_EQ(zeros.relative_half_width, 0.0);
  const Summary zero_median = summarize(std::vector<double>{-1.0, 0.0, 0.0, 0.0, 0.0, 1.0});
  EXPECT_EQ(zero_median.relative_half_width, std::numeric_limits<double>::infinity());

  EXPECT_THROW(median_interval(std::vector<double>{}, 0.95), InputError);
  EXPECT_THROW(median_interval(one_to(5), 1.0), InputError);
  EXPECT_THROW(median_interval(one_to(5), 0.0), InputError);
}

TEST(MedianInterval, LargeSamplesDoNotUnderflow) {
  const MedianInterval interval = median_interval(one_to(2000), 0.95);
  EXPECT_GE(interval.coverage, 0.95);
  EXPECT_LT(interval.coverage, 0.96);
  // Normal approximation: n/2 -+ 1.96 sqrt(n)/2 = 1000 -+ 43.8.
  EXPECT_NEAR(static_cast<double>(interval.lower_rank), 956.0, 2.0);
  EXPECT_EQ(interval.lower_rank + interval.upper_rank, 2001u);
}

TEST(PairedRatio, RoundDriftCancels) {
  // Every round the machine is slower or faster by a different factor; a is 10% slower than
  // b in every round. Unpaired medians would see the drift, the paired ratio does not.
  const std::vector<double> drift{1.0, 1.4, 0.9, 1.2, 1.0, 1.6, 1.1, 0.95};
  std::vector<double> a, b;
  for (const double f : drift) {
    b.push_back(0.2 * f);
    a.push_back(0.22 * f);
  }
  const PairedRatio r = paired_ratio(a, b);
  EXPECT_EQ(r.pairs, drift.size());
  EXPECT_NEAR(r.median, 1.1, 1e-12);
  EXPECT_NEAR(r.interval.low, 1.1, 1e-12);
  EXPECT_NEAR(r.interval.high, 1.1, 1e-12);
  EXPECT_TRUE(r.interval.reached_level);
}

TEST(PairedRatio, IntervalFromTheRatiosOrderStatistics) {
  // Ratios 1..10 (b = 1): the median 5.5 and, as for any 10 samples, ranks 2 and 9.
  const std::vector<double> ones(10, 1.0);
  const PairedRatio r = paired_ratio(one_to(10), ones);
  EXPECT_DOUBLE_EQ(r.median, 5.5);
  EXPECT_EQ(r.interval.low, 2.0);
  EXPECT_EQ(r.interval.high, 9.0);
}

TEST(PairedRatio, RejectsBadPairs) {
  EXPECT_THROW(paired_ratio(std::vector<double>{}, std::vector<double>{}), InputError);
  EXPECT_THROW(paired_ratio(one_to(3), one_to(4)), InputError);
  EXPECT_THROW(paired_ratio(one_to(2), std::vector<double>{1.0, 0.0}), InputError);
  EXPECT_THROW(paired_ratio(std::vector<double>{1.0, std::nan("")}, one_to(2)), InputError);
}

using Rounds = std::vector<std::vector<double>>;

TEST(RoundSlowdowns, RoundDriftCancels) {
  // The drift of PairedRatio.RoundDriftCancels; b the fastest in every round, a 10% slower.
  const std::vector<double> drift{1.0, 1.4, 0.9, 1.2, 1.0, 1.6, 1.1, 0.95};
  std::vector<std::vector<double>> samples(2);
  for (const double f : drift) {
    samples[0].push_back(0.22 * f);
    samples[1].push_back(0.2 * f);
  }
  const RoundSlowdowns s(samples);
  EXPECT_EQ(s.fastest(), 1u);
  EXPECT_NEAR(s.slowdown(0), 1.1, 1e-12);
  EXPECT_EQ(s.slowdown(1), 1.0);
  const RoundSlowdowns::Ratio a = s.relative(0, 1);
  EXPECT_NEAR(a.value, 1.1, 1e-12);
  EXPECT_NEAR(a.low, 1.1, 1e-12);
  EXPECT_NEAR(a.high, 1.1, 1e-12);
  const RoundSlowdowns::Ratio self = s.relative(1, 1);
  EXPECT_EQ(self.value, 1.0);
  EXPECT_EQ(self.low, 1.0);
  EXPECT_EQ(self.high, 1.0);
}

TEST(RoundSlowdowns, APairwiseCycleStillHasAFastestThatNoneUndercuts) {
  // Three rounds in which a beats b, b beats c and c beats a by their median paired ratios
  // (0.952, 0.909, 0.917): against any one of them another's paired ratio is below 1. By
  // slowdown against each round's fastest (a 1.1, b 1.05, c 1.1) b is the fastest and the
  // others' ratios to it are 1.1 / 1.05.
  const std::vector<std::vector<double>> samples{
      {1.0, 1.2, 1.1}, {1.05, 1.0, 1.2}, {1.2, 1.1, 1.0}};
  EXPECT_LT(paired_ratio(samples[0], samples[1]).median, 1.0);
  EXPECT_LT(paired_ratio(samples[1], samples[2]).median, 1.0);
  EXPECT_LT(paired_ratio(samples[2], samples[0]).median, 1.0);
  const RoundSlowdowns s(samples);
  EXPECT_EQ(s.fastest(), 1u);
  for (std::size_t c = 0; c < samples.size(); ++c) {
    const RoundSlowdowns::Ratio r = s.relative(c, s.fastest());
    EXPECT_GE(r.value, 1.0);
    EXPECT_LE(r.low, r.value);
    EXPECT_GE(r.high, r.value);
  }
  EXPECT_DOUBLE_EQ(s.relative(0, 1).value, 1.1 / 1.05);
}

TEST(RoundSlowdowns, TiesGoToTheFirst) {
  const RoundSlowdowns s(Rounds{{2.0, 1.0}, {1.0, 2.0}});
  EXPECT_EQ(s.fastest(), 0u);
  EXPECT_EQ(s.relative(1, 0).value, 1.0);
}

TEST(RoundSlowdowns, RejectsBadSamples) {
  EXPECT_THROW(RoundSlowdowns(Rounds{}), InputError);
  EXPECT_THROW(RoundSlowdowns(Rounds{std::vector<double>{}}), InputError);
  EXPECT_THROW(RoundSlowdowns(Rounds{{1.0, 2.0}, {1.0}}), InputError);
  EXPECT_THROW(RoundSlowdowns(Rounds{{1.0, 0.0}}), InputError);
  EXPECT_THROW(RoundSlowdowns(Rounds{{1.0, std::nan("")}}), InputError);
  EXPECT_THROW(RoundSlowdowns(Rounds{{1.0}}).relative(0, 0, 1.0), InputError);
}

TEST(Summarize, KnownValues) {
  const Summary s = summarize(std::vector<double>{4.0, 1.0, 3.0, 2.0, 10.0, 6.0});
  EXPECT_EQ(s.count, 6u);
  EXPECT_EQ(s.median, 3.5);
  EXPECT_EQ(s.min, 1.0);
  EXPECT_EQ(s.max, 10.0);
  EXPECT_DOUBLE_EQ(s.mean, 26.0 / 6.0);
  EXPECT_EQ(s.interval.low, 1.0);
  EXPECT_EQ(s.interval.high, 10.0);
  EXPECT_DOUBLE_EQ(s.relative_half_width, 4.5 / 3.5);
}

TEST(LoadImbalance, KnownValues) {
  EXPECT_EQ(load_imbalance(std::vector<double>{1.0, 1.0}), 0.0);
  EXPECT_DOUBLE_EQ(load_imbalance(std::vector<double>{2.0, 1.0, 0.0}), 0.5);  // mean 1, max 2
  EXPECT_DOUBLE_EQ(load_imbalance(std::vector<double>{4.0, 1.0, 1.0}), 0.5);  // mean 2, max 4
  EXPECT_EQ(load_imbalance(std::vector<double>{}), 0.0);
  EXPECT_EQ(load_imbalance(std::vector<double>{0.0, 0.0}), 0.0);
}

TEST(RepeatMeasurement, FixedCountRunsWarmUpThenRepetitions) {
  RepetitionPolicy p;
  p.warmup = 2;
  p.repeat = 5;
  int warm = 0, timed = 0;
  const RepetitionOutcome o = repeat_measurement(
      p, [&] { ++warm; }, [&] { return double(++timed); });
  EXPECT_EQ(warm, 2);
  EXPECT_EQ(timed, 5);
  EXPECT_EQ(o.warmup_runs, 2);
  EXPECT_EQ(o.repetitions, 5);
  EXPECT_EQ(o.stop, StopReason::kFixedCount);
}

TEST(RepeatMeasurement, AdaptiveStopsWhenTheIntervalIsNarrow) {
  RepetitionPolicy p;
  p.warmup = 0;
  p.repeat = 2;
  p.adaptive = true;
  p.target_relative_half_width = 0.02;
  p.time_budget_s = 1e9;
  // Constant samples: the interval is a point once 6 samples reach 95% coverage.
  const RepetitionOutcome o = repeat_measurement(
      p, [] {}, [] { return 1.0; });
  EXPECT_EQ(o.stop, StopReason::kTargetReached);
  EXPECT_EQ(o.repetitions, 6);
}

TEST(RepeatMeasurement, AdaptiveStopsAtTheMaximum) {
  RepetitionPolicy p;
  p.warmup = 0;
  p.repeat = 3;
  p.adaptive = true;
  p.time_budget_s = 1e9;
  p.max_repeat = 17;
  int i = 0;
  const RepetitionOutcome o = repeat_measurement(
      p, [] {}, [&] { return (++i % 2) ? 1.0 : 100.0; });
  EXPECT_EQ(o.stop, StopReason::kMaxRepeat);
  EXPECT_EQ(o.repetitions, 17);
}

TEST(RepeatMeasurement, AdaptiveStopsWhenTheBudgetIsSpent) {
  RepetitionPolicy p;
  p.warmup = 1;
  p.repeat = 4;
  p.adaptive = true;
  p.time_budget_s = 1e-12;  // spent by the first run: stop at the minimum count
  int i = 0;
  const RepetitionOutcome o = repeat_measurement(
      p, [] {}, [&] { return (++i % 2) ? 1.0 : 100.0; });
  EXPECT_EQ(o.stop, StopReason::kTimeBudget);
  EXPECT_EQ(o.repetitions, 4);
}

TEST(RepetitionPolicy, InvalidPoliciesAreRejected) {
  auto rejects = [](auto change) {
    RepetitionPolicy p;
    p.adaptive = true;
    change(p);
    EXPECT_THROW(validate(p), InputError);
  };
  rejects([](RepetitionPolicy& p) { p.warmup = -1; });
  rejects([](RepetitionPolicy& p) { p.repeat = 0; });
  rejects([](RepetitionPolicy& p) { p.level = 1.0; });
  rejects([](RepetitionPolicy& p) { p.target_relative_half_width = 0.0; });
  rejects([](RepetitionPolicy& p) { p.time_budget_s = -1.0; });
  rejects([](RepetitionPolicy& p) { p.max_repeat = 1; });
  EXPECT_NO_THROW(validate(RepetitionPolicy{}));
}

TEST(StopReason, RoundTripsThroughText) {
  for (const auto r : {StopReason::kFixedCount, StopReason::kTargetReached, StopReason::kTimeBudget,
                       StopReason::kMaxRepeat}) {
    EXPECT_EQ(parse_stop_reason(to_string(r)), r);
  }
  EXPECT_THROW(parse_stop_reason("bored"), InputError);
}

}  // namespace
}  // namespace contactlab
