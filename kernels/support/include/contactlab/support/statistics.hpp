// Statistics of repeated timings: median, extremes, a distribution-free confidence interval of
// the median, paired and per-round comparisons, load imbalance, and the repetition driver
// (warm-up, fixed or adaptive count).
#pragma once

#include <cstddef>
#include <functional>
#include <span>
#include <string_view>
#include <vector>

namespace contactlab {

// Median of the values (mean of the two middle ones for an even count). Throws InputError for
// an empty input or a NaN.
double median(std::span<const double> values);

// Distribution-free interval of the median from order statistics: [x_(k), x_(n+1-k)] (1-based
// ranks of the sorted sample) with the largest k whose coverage
//   P(k <= B <= n - k),  B ~ Binomial(n, 1/2)
// is at least `level`. It assumes only independent, identically distributed samples. Below
// 6 samples no k reaches 95%: the interval is then [min, max] and `coverage` says what it
// covers (1 - 2^(1-n)); `reached_level` is false.
struct MedianInterval {
  double low = 0.0;
  double high = 0.0;
  std::size_t lower_rank = 0;  // k, 1-based
  std::size_t upper_rank = 0;  // n + 1 - k
  double coverage = 0.0;       // exact coverage of the interval
  bool reached_level = false;  // coverage >= the requested level
};

// Throws InputError for an empty input, a NaN, or a level outside (0, 1).
MedianInterval median_interval(std::span<const double> values, double level = 0.95);

// P(k <= B <= n - k) for B ~ Binomial(n, 1/2): the coverage of [x_(k), x_(n+1-k)].
double order_statistic_coverage(std::size_t n, std::size_t k);

struct Summary {
  std::size_t count = 0;
  double median = 0.0;
  double min = 0.0;
  double max = 0.0;
  double mean = 0.0;
  double level = 0.95;  // requested confidence level of the interval
  MedianInterval interval;
  // Half the interval's width over the median: (high - low) / 2 / median; 0 when the median
  // is 0 and the interval is a point, +infinity when the median is 0 and the interval is not.
  double relative_half_width = 0.0;
};

Summary summarize(std::span<const double> values, double level = 0.95);

// Paired comparison of two configurations timed in the same rounds (a_i and b_i back to back,
// in round i): the median of the per-round ratios a_i / b_i and its order-statistic interval.
// Pairing cancels what a round shares (the machine's drift), so that differences of a few
// percent are resolved with far fewer rounds than by comparing two medians.
struct PairedRatio {
  std::size_t pairs = 0;
  double median = 0.0;  // of a_i / b_i
  MedianInterval interval;
};

// Throws InputError for no pairs, unequal lengths, a NaN, or some b_i <= 0.
PairedRatio paired_ratio(std::span<const double> a, std::span<const double> b, double level = 0.95);

// Several configurations timed in the same rounds (samples[c][r]: configuration c in round r),
// each compared with the round's fastest: its slowdown is the median over rounds of
// t_cr / min_j t_jr. Paired within rounds like paired_ratio, but one number per configuration,
// so the fastest (smallest slowdown) is well defined where pairwise median ratios can form a
// cycle, and every slowdown relative to it is >= 1.
class RoundSlowdowns {
 public:
  // Throws InputError for no configuration, no round, unequal round counts, a NaN or a time
  // <= 0.
  explicit RoundSlowdowns(const std::vector<std::vector<double>>& samples);

  double slowdown(std::size_t c) const { return slowdown_[c]; }
  // The smallest slowdown; the first of equal ones.
  std::size_t fastest() const { return fastest_; }

  // slowdown(c) / slowdown(reference) with a percentile-bootstrap interval over rounds (the
  // same resampled rounds for both; fixed seed, so a report is reproducible).
  struct Ratio {
    double value = 0.0;
    double low = 0.0;
    double high = 0.0;
  };
  Ratio relative(std::size_t c, std::size_t reference, double level = 0.95,
                 int resamples = 2000) const;

 private:
  std::vector<std::vector<double>> to_round_fastest_;  // t_cr / min_j t_jr
  std::vector<double> slowdown_;
  std::size_t fastest_ = 0;
};

// Load imbalance of one parallel loop from each thread's busy time:
// (t_max - t_mean) / t_max; 0 for no threads or when every time is 0.
double load_imbalance(std::span<const double> thread_busy_s);

// How many times to run: `warmup` runs whose results are dropped, then `repeat` timed runs;
// with `adaptive`, more timed runs until the median's interval (on the value the sample
// function returns) reaches `level` with a relative half-width <= `target_relative_half_width`,
// or the measurement (warm-up included) has used `time_budget_s` seconds, or `max_repeat` runs
// have been made. `repeat` is then the minimum.
struct RepetitionPolicy {
  int warmup = 1;
  int repeat = 3;
  bool adaptive = false;
  double target_relative_half_width = 0.02;
  double time_budget_s = 60.0;
  int max_repeat = 200;
  double level = 0.95;
};

// Throws InputError naming the bad field (the caller's option name is not known here).
void validate(const RepetitionPolicy& policy);

enum class StopReason { kFixedCount, kTargetReached, kTimeBudget, kMaxRepeat };
std::string_view to_string(StopReason reason);
StopReason parse_stop_reason(std::string_view text);  // throws InputError

struct RepetitionOutcome {
  int warmup_runs = 0;
  int repetitions = 0;
  StopReason stop = StopReason::kFixedCount;
  double elapsed_s = 0.0;  // wall time of all runs, warm-up included
};

// Calls warm_up() policy.warmup times, then sample() until the policy says stop. sample()
// returns the value whose median must converge (the caller keeps everything else it measures).
RepetitionOutcome repeat_measurement(const RepetitionPolicy& policy,
                                     const std::function<void()>& warm_up,
                                     const std::function<double()>& sample);

}  // namespace contactlab
