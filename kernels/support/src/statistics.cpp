#include "contactlab/support/statistics.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "contactlab/kernels/error.hpp"

namespace contactlab {
namespace {

std::vector<double> sorted_copy(std::span<const double> values, const char* function) {
  if (values.empty()) throw InputError(std::string(function) + ": no samples");
  for (const double v : values) {
    if (std::isnan(v)) throw InputError(std::string(function) + ": a sample is NaN");
  }
  std::vector<double> sorted(values.begin(), values.end());
  std::sort(sorted.begin(), sorted.end());
  return sorted;
}

double median_of_sorted(const std::vector<double>& sorted) {
  const std::size_t m = sorted.size() / 2;
  return sorted.size() % 2 ? sorted[m] : 0.5 * (sorted[m - 1] + sorted[m]);
}

// P(B = i) for B ~ Binomial(n, 1/2), in log space so that large n does not underflow early.
double binomial_half_pmf(std::size_t n, std::size_t i) {
  const double dn = static_cast<double>(n), di = static_cast<double>(i);
  return std::exp(std::lgamma(dn + 1.0) - std::lgamma(di + 1.0) - std::lgamma(dn - di + 1.0) -
                  dn * std::log(2.0));
}

}  // namespace

double median(std::span<const double> values) {
  return median_of_sorted(sorted_copy(values, "median"));
}

double order_statistic_coverage(std::size_t n, std::size_t k) {
  if (n == 0 || k == 0 || 2 * k > n + 1) {
    throw InputError("order_statistic_coverage: rank k = " + std::to_string(k) +
                     " is outside 1..(n+1)/2 for n = " + std::to_string(n));
  }
  double below = 0.0;  // P(B <= k - 1)
  for (std::size_t i = 0; i < k; ++i) below += binomial_half_pmf(n, i);
  return std::max(0.0, 1.0 - 2.0 * below);
}

MedianInterval median_interval(std::span<const double> values, double level) {
  if (!(level > 0.0 && level < 1.0)) {
    throw InputError("median_interval: level must be in (0, 1), got " + number_text(level));
  }
  const std::vector<double> sorted = sorted_copy(values, "median_interval");
  const std::size_t n = sorted.size();
  // Coverage falls as k grows: take the largest k that still reaches the level.
  std::size_t k = 1;
  double below = binomial_half_pmf(n, 0);  // P(B <= k - 1)
  double coverage = std::max(0.0, 1.0 - 2.0 * below);
  while (2 * (k + 1) <= n + 1) {
    const double next_below = below + binomial_half_pmf(n, k);
    const double next_coverage = std::max(0.0, 1.0 - 2.0 * next_below);
    if (next_coverage < level) break;
    ++k;
    below = next_below;
    coverage = next_coverage;
  }
  MedianInterval interval;
  interval.lower_rank = k;
  interval.upper_rank = n + 1 - k;
  interval.low = sorted[k - 1];
  interval.high = sorted[n - k];
  interval.coverage = coverage;
  interval.reached_level = coverage >= level;
  return interval;
}

Summary summarize(std::span<const double> values, double level) {
  const std::vector<double> sorted = sorted_copy(values, "summarize");
  Summary s;
  s.count = sorted.size();
  s.median = median_of_sorted(sorted);
  s.min = sorted.front();
  s.max = sorted.back();
  double sum = 0.0;
  for (const double v : sorted) sum += v;
  s.mean = sum / static_cast<double>(sorted.size());
  s.level = level;
  s.interval = median_interval(sorted, level);
  const double half_width = 0.5 * (s.interval.high - s.interval.low);
  if (s.median != 0.0) {
    s.relative_half_width = half_width / std::abs(s.median);
  } else {
    s.relative_half_width = half_width == 0.0 ? 0.0 : std::numeric_limits<double>::infinity();
  }
  return s;
}

PairedRatio paired_ratio(std::span<const double> a, std::span<const double> b, double level) {
  if (a.size() != b.size()) {
    throw InputError("paired_ratio: " + std::to_string(a.size()) + " and " +
                     std::to_string(b.size()) + " samples: pairs need equal counts");
  }
  std::vector<double> ratios;
  ratios.reserve(a.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (!(b[i] > 0.0)) {
      throw InputError("paired_ratio: round " + std::to_string(i) + " divides by " +
                       std::to_string(b[i]) + " (need > 0)");
    }
    ratios.push_back(a[i] / b[i]);
  }
  PairedRatio result;
  result.pairs = ratios.size();
  result.median = median(ratios);  // throws for no pairs or a NaN
  result.interval = median_interval(ratios, level);
  return result;
}

RoundSlowdowns::RoundSlowdowns(const std::vector<std::vector<double>>& samples) {
  if (samples.empty() || samples.front().empty()) {
    throw InputError("round slowdowns: no configuration or no round to compare");
  }
  const std::size_t rounds = samples.front().size();
  std::vector<double> round_fastest(rounds, std::numeric_limits<double>::infinity());
  for (std::size_t c = 0; c < samples.size(); ++c) {
    if (samples[c].size() != rounds) {
      throw InputError("round slowdowns: configuration " + std::to_string(c) + " has " +
                       std::to_string(samples[c].size()) + " rounds, the first " +
                       std::to_string(rounds));
    }
    for (std::size_t r = 0; r < rounds; ++r) {
      if (!(samples[c][r] > 0.0)) {
        throw InputError("round slowdowns: configuration " + std::to_string(c) + ", round " +
                         std::to_string(r) + " took " + std::to_string(samples[c][r]) +
                         " (need > 0)");
      }
      round_fastest[r] = std::min(round_fastest[r], samples[c][r]);
    }
  }
  to_round_fastest_.resize(samples.size());
  for (std::size_t c = 0; c < samples.size(); ++c) {
    for (std::size_t r = 0; r < rounds; ++r) {
      to_round_fastest_[c].push_back(samples[c][r] / round_fastest[r]);
    }
    slowdown_.push_back(median(to_round_fastest_[c]));
    if (slowdown_[c] < slowdown_[fastest_]) fastest_ = c;
  }
}

RoundSlowdowns::Ratio RoundSlowdowns::relative(std::size_t c, std::size_t reference, double level,
                                               int resamples) const {
  if (!(level > 0.0 && level < 1.0) || resamples < 1) {
    throw InputError("round slowdowns: level " + number_text(level) + " and " +
                     std::to_string(resamples) + " resamples (need a level in (0, 1), >= 1)");
  }
  const std::vector<double>& of_c = to_round_fastest_.at(c);
  const std::vector<double>& of_reference = to_round_fastest_.at(reference);
  Ratio ratio;
  ratio.value = slowdown_[c] / slowdown_[reference];
  std::mt19937_64 random(20131001);
  std::uniform_int_distribution<std::size_t> pick(0, of_c.size() - 1);
  std::vector<double> drawn_c(of_c.size()), drawn_reference(of_c.size()), ratios;
  ratios.reserve(static_cast<std::size_t>(resamples));
  for (int b = 0; b < resamples; ++b) {
    for (std::size_t i = 0; i < of_c.size(); ++i) {
      const std::size_t r = pick(random);
      drawn_c[i] = of_c[r];
      drawn_reference[i] = of_reference[r];
    }
    ratios.push_back(median(drawn_c) / median(drawn_reference));
  }
  std::sort(ratios.begin(), ratios.end());
  const auto at = [&](double q) {
    const auto i =
        static_cast<std::size_t>(std::lround(q * static_cast<double>(ratios.size() - 1)));
    return ratios[std::min(i, ratios.size() - 1)];
  };
  // A median's bootstrap distribution is lumpy at a few rounds: the interval is widened to hold
  // the estimate rather than report one that excludes it.
  ratio.low = std::min(ratio.value, at(0.5 * (1.0 - level)));
  ratio.high = std::max(ratio.value, at(0.5 * (1.0 + level)));
  return ratio;
}

double load_imbalance(std::span<const double> thread_busy_s) {
  if (thread_busy_s.empty()) return 0.0;
  double max = 0.0, sum = 0.0;
  for (const double t : thread_busy_s) {
    max = std::max(max, t);
    sum += t;
  }
  if (max <= 0.0) return 0.0;
  const double mean = sum / static_cast<double>(thread_busy_s.size());
  return (max - mean) / max;
}

void validate(const RepetitionPolicy& policy) {
  auto fail = [](const std::string& what) { throw InputError("repetition policy: " + what); };
  if (policy.warmup < 0) fail("warm-up runs must be >= 0, got " + std::to_string(policy.warmup));
  if (policy.repeat < 1) fail("repetitions must be >= 1, got " + std::to_string(policy.repeat));
  if (!(policy.level > 0.0 && policy.level < 1.0)) {
    fail("confidence level must be in (0, 1), got " + std::to_string(policy.level));
  }
  if (!policy.adaptive) return;
  if (!(policy.target_relative_half_width > 0.0 && policy.target_relative_half_width < 1.0)) {
    fail("target relative half-width must be in (0, 1), got " +
         std::to_string(policy.target_relative_half_width));
  }
  if (!(policy.time_budget_s > 0.0) || !std::isfinite(policy.time_budget_s)) {
    fail("time budget must be a positive number of seconds, got " +
         std::to_string(policy.time_budget_s));
  }
  if (policy.max_repeat < policy.repeat) {
    fail("maximum repetitions (" + std::to_string(policy.max_repeat) +
         ") must be >= repetitions (" + std::to_string(policy.repeat) + ")");
  }
}

std::string_view to_string(StopReason reason) {
  switch (reason) {
    case StopReason::kFixedCount:
      return "fixed_count";
    case StopReason::kTargetReached:
      return "target_reached";
    case StopReason::kTimeBudget:
      return "time_budget";
    case StopReason::kMaxRepeat:
      return "max_repeat";
  }
  return "fixed_count";
}

StopReason parse_stop_reason(std::string_view text) {
  for (const auto r : {StopReason::kFixedCount, StopReason::kTargetReached, StopReason::kTimeBudget,
                       StopReason::kMaxRepeat}) {
    if (text == to_string(r)) return r;
  }
  throw InputError("unknown stop reason '" + std::string(text) +
                   "' (expected fixed_count, target_reached, time_budget or max_repeat)");
}

RepetitionOutcome repeat_measurement(const RepetitionPolicy& policy,
                                     const std::function<void()>& warm_up,
                                     const std::function<double()>& sample) {
  validate(policy);
  RepetitionOutcome outcome;
  const auto start = std::chrono::steady_clock::now();
  auto seconds_since_start = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  for (int i = 0; i < policy.warmup; ++i) {
    warm_up();
    ++outcome.warmup_runs;
  }
  std::vector<double> values;
  for (;;) {
    values.push_back(sample());
    ++outcome.repetitions;
    const double elapsed = seconds_since_start();
    if (outcome.repetitions < policy.repeat) continue;
    if (!policy.adaptive) {
      outcome.stop = StopReason::kFixedCount;
      break;
    }
    const Summary s = summarize(values, policy.level);
    if (s.interval.reached_level && s.relative_half_width <= policy.target_relative_half_width) {
      outcome.stop = StopReason::kTargetReached;
      break;
    }
    if (elapsed >= policy.time_budget_s) {
      outcome.stop = StopReason::kTimeBudget;
      break;
    }
    if (outcome.repetitions >= policy.max_repeat) {
      outcome.stop = StopReason::kMaxRepeat;
      break;
    }
  }
  outcome.elapsed_s = seconds_since_start();
  return outcome;
}

}  // namespace contactlab
