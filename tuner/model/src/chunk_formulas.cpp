#include "contactlab/tuner_model/chunk_formulas.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace contactlab::tuner {

namespace {

void check_threads(const char* function, int threads) {
  if (threads < 1) {
    throw std::invalid_argument(std::string(function) + ": threads = " + std::to_string(threads) +
                                " must be >= 1");
  }
}

std::uint64_t ceil_div(std::uint64_t a, std::uint64_t b) { return (a + b - 1) / b; }

int to_chunk(std::uint64_t chunk) {
  return static_cast<int>(std::clamp<std::uint64_t>(
      chunk, 1, static_cast<std::uint64_t>(std::numeric_limits<int>::max())));
}

// Batches of P chunks of ceil(R / (x P)), x from `next_x(R)`.
template <class NextX>
std::vector<std::uint64_t> factoring_batches(std::uint64_t iterations, int threads, NextX next_x) {
  std::vector<std::uint64_t> sizes;
  const auto p = static_cast<double>(threads);
  std::uint64_t remaining = iterations;
  while (remaining > 0) {
    const double x = next_x(remaining);
    const auto chunk = std::max<std::uint64_t>(
        1, static_cast<std::uint64_t>(std::ceil(static_cast<double>(remaining) / (x * p))));
    for (int t = 0; t < threads && remaining > 0; ++t) {
      const std::uint64_t size = std::min(chunk, remaining);
      sizes.push_back(size);
      remaining -= size;
    }
  }
  return sizes;
}

}  // namespace

IterationTimeStatistics iteration_time_statistics(WorkView work, const MachineCosts& costs) {
  IterationTimeStatistics stats;
  stats.iterations = work.size();
  if (work.size() == 0) return stats;
  auto seconds_of = [&](std::size_t i) {
    const double homes = work.homes.empty() ? 1.0 : work.homes[i];
    const double builds = work.builds.empty() ? 1.0 : work.builds[i];
    return costs.seconds_per_iteration + homes * costs.seconds_per_home +
           builds * costs.seconds_per_build + work.tests[i] * costs.seconds_per_test;
  };
  const auto m = static_cast<double>(work.size());
  double tests_sum = 0.0, seconds_sum = 0.0;
  for (std::size_t i = 0; i < work.size(); ++i) {
    tests_sum += work.tests[i];
    seconds_sum += seconds_of(i);
  }
  stats.mean_tests = tests_sum / m;
  stats.mean_seconds = seconds_sum / m;
  double tests_squares = 0.0, seconds_squares = 0.0;
  for (std::size_t i = 0; i < work.size(); ++i) {
    const double tests = static_cast<double>(work.tests[i]) - stats.mean_tests;
    const double seconds = seconds_of(i) - stats.mean_seconds;
    tests_squares += tests * tests;
    seconds_squares += seconds * seconds;
  }
  stats.stddev_tests = std::sqrt(tests_squares / m);
  stats.stddev_seconds = std::sqrt(seconds_squares / m);
  return stats;
}

int kruskal_weiss_chunk(std::uint64_t iterations, int threads, double overhead_seconds,
                        double sigma_seconds) {
  check_threads("kruskal_weiss_chunk", threads);
  if (!(overhead_seconds >= 0.0) || !(sigma_seconds >= 0.0)) {
    throw std::invalid_argument("kruskal_weiss_chunk: h = " + std::to_string(overhead_seconds) +
                                " s, sigma = " + std::to_string(sigma_seconds) + " s must be >= 0");
  }
  const std::uint64_t largest =
      std::max<std::uint64_t>(1, ceil_div(iterations, static_cast<std::uint64_t>(threads)));
  if (threads == 1 || sigma_seconds == 0.0) return to_chunk(largest);
  const double p = threads;
  const double k = std::pow(std::sqrt(2.0) * static_cast<double>(iterations) * overhead_seconds /
                                (sigma_seconds * p * std::sqrt(std::log(p))),
                            2.0 / 3.0);
  if (!(k < static_cast<double>(largest))) return to_chunk(largest);
  return to_chunk(static_cast<std::uint64_t>(std::llround(std::max(k, 1.0))));
}

int kruskal_weiss_chunk(WorkView work, int threads, const MachineCosts& costs) {
  const IterationTimeStatistics stats = iteration_time_statistics(work, costs);
  return kruskal_weiss_chunk(work.size(), threads, costs.seconds_per_grab, stats.stddev_seconds);
}

std::vector<std::uint64_t> factoring_chunk_sequence(std::uint64_t iterations, int threads,
                                                    double x) {
  check_threads("factoring_chunk_sequence", threads);
  if (!(x >= 1.0)) {
    throw std::invalid_argument("factoring_chunk_sequence: x = " + std::to_string(x) +
                                " must be >= 1");
  }
  return factoring_batches(iterations, threads, [x](std::uint64_t) { return x; });
}

int factoring_chunk(std::uint64_t iterations, int threads, double x) {
  check_threads("factoring_chunk", threads);
  if (!(x >= 1.0)) {
    throw std::invalid_argument("factoring_chunk: x = " + std::to_string(x) + " must be >= 1");
  }
  return to_chunk(static_cast<std::uint64_t>(
      std::ceil(static_cast<double>(iterations) / (x * static_cast<double>(threads)))));
}

std::vector<std::uint64_t> factoring_chunk_sequence(std::uint64_t iterations, int threads,
                                                    double mean_seconds, double sigma_seconds) {
  check_threads("factoring_chunk_sequence", threads);
  if (!(mean_seconds > 0.0) || !(sigma_seconds >= 0.0)) {
    throw std::invalid_argument("factoring_chunk_sequence: mean = " + std::to_string(mean_seconds) +
                                " s, sigma = " + std::to_string(sigma_seconds) +
                                " s (need mean > 0, sigma >= 0)");
  }
  const double p = threads;
  return factoring_batches(iterations, threads, [&](std::uint64_t remaining) {
    const double b =
        p * sigma_seconds / (2.0 * std::sqrt(static_cast<double>(remaining)) * mean_seconds);
    return 1.0 + b * b + b * std::sqrt(b * b + 2.0);
  });
}

int guided_self_scheduling_chunk(std::uint64_t iterations, int threads) {
  check_threads("guided_self_scheduling_chunk", threads);
  return to_chunk(ceil_div(iterations, static_cast<std::uint64_t>(threads)));
}

int block_chunk(std::uint64_t iterations, int threads) {
  check_threads("block_chunk", threads);
  return to_chunk(ceil_div(iterations, static_cast<std::uint64_t>(threads)));
}

int eighth_block_chunk(std::uint64_t iterations, int threads) {
  check_threads("eighth_block_chunk", threads);
  return to_chunk(ceil_div(iterations, 8 * static_cast<std::uint64_t>(threads)));
}

std::vector<NamedChunk> classic_chunks(WorkView work, int threads, const MachineCosts& costs) {
  check_threads("classic_chunks", threads);
  const IterationTimeStatistics stats = iteration_time_statistics(work, costs);
  const std::uint64_t n = work.size();
  auto inputs = [&](bool with_costs) {
    std::ostringstream text;
    text << "N=" << n << ",P=" << threads;
    if (with_costs) {
      text << ",h=" << costs.seconds_per_grab << "s,sigma=" << stats.stddev_seconds << "s";
    }
    return text.str();
  };
  return {
      {"kruskal_weiss", kruskal_weiss_chunk(work, threads, costs), inputs(true)},
      {"factoring", factoring_chunk(n, threads), inputs(false) + ",x=2"},
      {"guided_self_scheduling", guided_self_scheduling_chunk(n, threads), inputs(false)},
      {"block", block_chunk(n, threads), inputs(false)},
      {"eighth_block", eighth_block_chunk(n, threads), inputs(false)},
  };
}

}  // namespace contactlab::tuner
