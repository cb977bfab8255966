#include "contactlab/tuner_model/schedule_model.hpp"

#include <algorithm>
#include <limits>
#include <queue>
#include <stdexcept>
#include <string>
#include <tuple>

#include "contactlab/kernels/balanced_blocks.hpp"

namespace contactlab::tuner {

namespace {

constexpr std::uint64_t kNoChunkYet = std::numeric_limits<std::uint64_t>::max();

std::string schedule_text(const Schedule& schedule) {
  return std::string(to_string(schedule.kind)) + "," + std::to_string(schedule.chunk);
}

void check_threads(const char* function, int threads) {
  if (threads < 1) {
    throw std::invalid_argument(std::string(function) + ": threads = " + std::to_string(threads) +
                                " must be >= 1");
  }
}

void check_schedule(const char* function, const Schedule& schedule) {
  if (!has_valid_chunk(schedule)) {
    throw std::invalid_argument(std::string(function) + ": schedule " + schedule_text(schedule) +
                                ": chunk must be >= 1 (or 0 = block with static, always 0 with "
                                "balanced)");
  }
}

template <class Count, class Sum>
std::vector<Sum> prefix_sums(std::span<const Count> counts) {
  std::vector<Sum> prefix(counts.size() + 1);
  prefix[0] = 0;
  for (std::size_t i = 0; i < counts.size(); ++i) prefix[i + 1] = prefix[i] + counts[i];
  return prefix;
}

// Builds the per-thread shares chunk by chunk.
class ShareBuilder {
 public:
  ShareBuilder(const PreparedWork& work, int threads, const MachineCosts& costs,
               bool self_scheduled, bool record_chunks)
      : work_(work),
        costs_(costs),
        self_scheduled_(self_scheduled),
        record_chunks_(record_chunks),
        last_end_(static_cast<std::size_t>(threads), kNoChunkYet) {
    outcome_.threads.resize(static_cast<std::size_t>(threads));
    outcome_.self_scheduled = self_scheduled;
  }

  std::uint64_t iterations() const { return work_.iterations(); }

  // Time `thread` spends before its first chunk (the balanced schedule's weighing).
  void add_seconds(int thread, double seconds) {
    outcome_.threads[static_cast<std::size_t>(thread)].seconds += seconds;
  }

  // Gives [begin, end) to `thread`; returns the chunk's seconds.
  double assign(int thread, std::uint64_t begin, std::uint64_t end) {
    ThreadShare& share = outcome_.threads[static_cast<std::size_t>(thread)];
    const WorkView& view = work_.view();
    const std::uint64_t iterations = end - begin;
    const std::uint64_t tests = work_.tests(begin, end);
    const std::uint64_t homes = work_.homes(begin, end);
    std::uint64_t builds = work_.builds(begin, end);
    const bool breaks = last_end_[static_cast<std::size_t>(thread)] != begin;
    std::uint64_t cold = 0;
    if (breaks && begin < end) {
      cold = view.tests[begin];
      // The thread's previous iteration was elsewhere: the first home builds its ranges anew.
      const bool has_home = view.homes.empty() || view.homes[begin] > 0;
      const bool builds_anyway = view.builds.empty() || view.builds[begin] != 0;
      if (has_home && !builds_anyway) ++builds;
    }
    share.tests += tests;
    share.iterations += iterations;
    share.homes += homes;
    share.builds += builds;
    share.chunks += 1;
    if (self_scheduled_) share.grabs += 1;
    if (breaks) {
      share.stream_breaks += 1;
      share.cold_tests += cold;
    }
    last_end_[static_cast<std::size_t>(thread)] = end;
    if (record_chunks_) outcome_.chunks.push_back({begin, end, thread});
    const double seconds =
        static_cast<double>(tests) * costs_.seconds_per_test +
        static_cast<double>(iterations) * costs_.seconds_per_iteration +
        static_cast<double>(homes) * costs_.seconds_per_home +
        static_cast<double>(builds) * costs_.seconds_per_build +
        (self_scheduled_ ? costs_.seconds_per_grab : costs_.seconds_per_static_chunk) +
        (breaks ? costs_.seconds_per_stream_break +
                      static_cast<double>(cold) * costs_.seconds_per_cold_test
                : 0.0);
    share.seconds += seconds;
    return seconds;
  }

  // The empty grab that ends each thread's self-scheduled loop.
  void final_grabs() {
    for (ThreadShare& share : outcome_.threads) {
      share.grabs += 1;
      share.seconds += costs_.seconds_per_grab;
    }
  }

  ScheduleOutcome finish() {
    std::vector<double> seconds;
    std::vector<std::uint64_t> tests;
    double max_seconds = 0.0;
    for (const ThreadShare& share : outcome_.threads) {
      seconds.push_back(share.seconds);
      tests.push_back(share.tests);
      max_seconds = std::max(max_seconds, share.seconds);
      outcome_.max_thread_tests = std::max(outcome_.max_thread_tests, share.tests);
      outcome_.total_chunks += share.chunks;
    }
    outcome_.makespan_seconds = costs_.seconds_per_region + max_seconds;
    outcome_.imbalance = imbalance(std::span<const double>(seconds));
    outcome_.test_imbalance = imbalance(std::span<const std::uint64_t>(tests));
    return std::move(outcome_);
  }

 private:
  const PreparedWork& work_;
  MachineCosts costs_;
  bool self_scheduled_;
  bool record_chunks_;
  std::vector<std::uint64_t> last_end_;  // where each thread's previous chunk ended
  ScheduleOutcome outcome_;
};

ScheduleOutcome simulate_static(const PreparedWork& work, int threads, int chunk,
                                const MachineCosts& costs, bool record_chunks) {
  ShareBuilder builder(work, threads, costs, false, record_chunks);
  const std::uint64_t m = work.iterations();
  const auto p = static_cast<std::uint64_t>(threads);
  if (chunk == 0) {
    // gomp_iter_static_next with chunk_size 0: q = n / nthreads, t = n % nthreads; threads
    // below t take q + 1; s0 = q * i + t (t zeroed for them), e0 = s0 + q.
    const std::uint64_t q = m / p, r = m % p;
    for (std::uint64_t t = 0; t < p; ++t) {
      const std::uint64_t begin = t * q + std::min(t, r);
      const std::uint64_t end = begin + q + (t < r ? 1 : 0);
      if (begin < end) builder.assign(static_cast<int>(t), begin, end);
    }
  } else {
    const auto k = static_cast<std::uint64_t>(chunk);
    for (std::uint64_t c = 0; c * k < m; ++c) {
      builder.assign(static_cast<int>(c % p), c * k, std::min(m, (c + 1) * k));
    }
  }
  return builder.finish();
}

// Blocks of equal tests plus kHomeTests per home (schedule_model.hpp, "balanced"), after the
// weighing.
ScheduleOutcome simulate_balanced(const PreparedWork& work, int threads, const MachineCosts& costs,
                                  bool record_chunks) {
  ShareBuilder builder(work, threads, costs, false, record_chunks);
  const std::uint64_t m = work.iterations();
  const auto p = static_cast<std::uint64_t>(threads);
  auto prefix = [&](std::uint64_t k) { return work.tests(0, k) + kHomeTests * work.homes(0, k); };
  const std::uint64_t total = prefix(m);
  // Before the loop each thread weighs an equal slice: a pass over its iterations with a
  // stencil build per cell, at the weighing's constants (the loop's where none were fitted:
  // MachineCosts). One thread does not weigh: it runs the whole loop, as the block (the
  // detector's BalancedBlocks::block). Priced
  // at one thread too, the weighing entered the emulation's one-thread anchor, which then
  // scaled every thread count's loop by 0.67 - 0.77 (`emulate threads`: the full stencil's
  // balanced blocks checked -13 % at two threads).
  const double per_iteration = costs.seconds_per_weighed_iteration >= 0.0
                                   ? costs.seconds_per_weighed_iteration
                                   : costs.seconds_per_iteration;
  const double per_build = costs.seconds_per_weighed_build >= 0.0 ? costs.seconds_per_weighed_build
                                                                  : costs.seconds_per_build;
  for (std::uint64_t t = 0; t < p && p > 1; ++t) {
    const std::uint64_t first = m * t / p, last = m * (t + 1) / p;
    builder.add_seconds(static_cast<int>(t),
                        static_cast<double>(last - first) * per_iteration +
                            static_cast<double>(work.builds(first, last)) * per_build);
  }
  std::uint64_t begin = 0;
  for (std::uint64_t t = 0; t < p; ++t) {
    std::uint64_t end = m;
    if (t + 1 < p) {
      // The first k whose prefix reaches the target (the detector's BalancedBlocks bounds).
      const std::uint64_t target = total / p * (t + 1) + total % p * (t + 1) / p;
      std::uint64_t lo = begin, hi = m;
      while (lo < hi) {
        const std::uint64_t mid = lo + (hi - lo) / 2;
        if (prefix(mid) >= target) {
          hi = mid;
        } else {
          lo = mid + 1;
        }
      }
      end = lo;
    }
    if (begin < end) builder.assign(static_cast<int>(t), begin, end);
    begin = end;
  }
  return builder.finish();
}

// Greedy self-scheduling: the next chunk goes to the thread whose clock is lowest (ties: fewer
// chunks taken, then lowest id). next_size(remaining) gives the next chunk's size.
template <class NextSize>
ScheduleOutcome simulate_self_scheduled(const PreparedWork& work, int threads, NextSize next_size,
                                        const MachineCosts& costs, bool record_chunks) {
  ShareBuilder builder(work, threads, costs, true, record_chunks);
  using Clock = std::tuple<double, std::uint64_t, int>;  // free at, chunks taken, thread id
  std::priority_queue<Clock, std::vector<Clock>, std::greater<>> free_threads;
  for (int t = 0; t < threads; ++t) free_threads.emplace(0.0, 0, t);
  const std::uint64_t m = builder.iterations();
  std::uint64_t next = 0;
  while (next < m) {
    const std::uint64_t size = std::min<std::uint64_t>(next_size(m - next), m - next);
    auto [free_at, taken, thread] = free_threads.top();
    free_threads.pop();
    free_at += builder.assign(thread, next, next + size);
    free_threads.emplace(free_at, taken + 1, thread);
    next += size;
  }
  builder.final_grabs();
  return builder.finish();
}

std::uint64_t ceil_div(std::uint64_t a, std::uint64_t b) { return (a + b - 1) / b; }

// libgomp/iter.c, gomp_iter_guided_next{,_locked}:
//   n = (ws->end - start) / ws->incr;  q = (n + nthreads - 1) / nthreads;
//   if (q < ws->chunk_size) q = ws->chunk_size;  if (q <= n) end = start + q; else end = ws->end;
std::uint64_t guided_next_size(std::uint64_t remaining, std::uint64_t threads,
                               std::uint64_t chunk) {
  const std::uint64_t q = std::max(ceil_div(remaining, threads), chunk);
  return std::min(q, remaining);
}

}  // namespace

WorkView::WorkView(std::span<const std::uint32_t> tests_, std::span<const std::uint32_t> homes_,
                   std::span<const std::uint8_t> builds_)
    : tests(tests_), homes(homes_), builds(builds_) {
  if ((!homes.empty() && homes.size() != tests.size()) ||
      (!builds.empty() && builds.size() != tests.size())) {
    throw std::invalid_argument("WorkView: " + std::to_string(tests.size()) + " iterations but " +
                                std::to_string(homes.size()) + " home counts and " +
                                std::to_string(builds.size()) + " build flags");
  }
}

PreparedWork::PreparedWork(WorkView work)
    : work_(work), tests_(prefix_sums<std::uint32_t, std::uint64_t>(work.tests)) {
  if (!work.homes.empty()) homes_ = prefix_sums<std::uint32_t, std::uint64_t>(work.homes);
  if (!work.builds.empty()) builds_ = prefix_sums<std::uint8_t, std::uint64_t>(work.builds);
}

std::uint64_t PreparedWork::tests(std::uint64_t begin, std::uint64_t end) const {
  return tests_[end] - tests_[begin];
}

std::uint64_t PreparedWork::homes(std::uint64_t begin, std::uint64_t end) const {
  return homes_.empty() ? end - begin : homes_[end] - homes_[begin];
}

std::uint64_t PreparedWork::builds(std::uint64_t begin, std::uint64_t end) const {
  return builds_.empty() ? end - begin : builds_[end] - builds_[begin];
}

MachineCosts MachineCosts::tests_only() {
  MachineCosts costs;
  costs.seconds_per_test = 1.0;
  costs.seconds_per_iteration = 0.0;
  costs.seconds_per_home = 0.0;
  costs.seconds_per_build = 0.0;
  costs.seconds_per_static_chunk = 0.0;
  costs.seconds_per_grab = 0.0;
  costs.seconds_per_stream_break = 0.0;
  costs.seconds_per_cold_test = 0.0;
  costs.seconds_per_region = 0.0;
  return costs;
}

ScheduleOutcome simulate_schedule(WorkView work, int threads, const Schedule& schedule,
                                  const MachineCosts& costs, bool record_chunks) {
  return simulate_schedule(PreparedWork(work), threads, schedule, costs, record_chunks);
}

ScheduleOutcome simulate_schedule(const PreparedWork& work, int threads, const Schedule& schedule,
                                  const MachineCosts& costs, bool record_chunks) {
  check_threads("simulate_schedule", threads);
  check_schedule("simulate_schedule", schedule);
  const auto chunk = static_cast<std::uint64_t>(schedule.chunk);
  const auto p = static_cast<std::uint64_t>(threads);
  switch (schedule.kind) {
    case ScheduleKind::kStatic:
      return simulate_static(work, threads, schedule.chunk, costs, record_chunks);
    case ScheduleKind::kBalanced:
      return simulate_balanced(work, threads, costs, record_chunks);
    case ScheduleKind::kDynamic:
      return simulate_self_scheduled(
          work, threads, [chunk](std::uint64_t) { return chunk; }, costs, record_chunks);
    case ScheduleKind::kGuided:
      return simulate_self_scheduled(
          work, threads,
          [chunk, p](std::uint64_t remaining) { return guided_next_size(remaining, p, chunk); },
          costs, record_chunks);
  }
  throw std::invalid_argument("simulate_schedule: unknown schedule kind");
}

ScheduleOutcome simulate_chunk_sequence(WorkView work, int threads,
                                        std::span<const std::uint64_t> chunk_sizes,
                                        const MachineCosts& costs, bool record_chunks) {
  check_threads("simulate_chunk_sequence", threads);
  if (chunk_sizes.empty()) {
    throw std::invalid_argument("simulate_chunk_sequence: the chunk-size sequence is empty");
  }
  for (std::size_t j = 0; j < chunk_sizes.size(); ++j) {
    if (chunk_sizes[j] == 0) {
      throw std::invalid_argument("simulate_chunk_sequence: chunk size " + std::to_string(j) +
                                  " is 0");
    }
  }
  std::size_t index = 0;
  auto next_size = [&](std::uint64_t) {
    const std::uint64_t size = chunk_sizes[std::min(index, chunk_sizes.size() - 1)];
    ++index;
    return size;
  };
  return simulate_self_scheduled(PreparedWork(work), threads, next_size, costs, record_chunks);
}

std::vector<std::uint64_t> self_scheduling_chunk_sizes(std::uint64_t iterations, int threads,
                                                       const Schedule& schedule) {
  check_threads("self_scheduling_chunk_sizes", threads);
  if (schedule.kind == ScheduleKind::kStatic || schedule.chunk < 1) {
    throw std::invalid_argument("self_scheduling_chunk_sizes: schedule " + schedule_text(schedule) +
                                " is not dynamic or guided with chunk >= 1");
  }
  const auto chunk = static_cast<std::uint64_t>(schedule.chunk);
  const auto p = static_cast<std::uint64_t>(threads);
  std::vector<std::uint64_t> sizes;
  for (std::uint64_t remaining = iterations; remaining > 0;) {
    const std::uint64_t size = schedule.kind == ScheduleKind::kDynamic
                                   ? std::min(chunk, remaining)
                                   : guided_next_size(remaining, p, chunk);
    sizes.push_back(size);
    remaining -= size;
  }
  return sizes;
}

std::vector<std::uint64_t> thread_tests(WorkView work, int threads, const Schedule& schedule) {
  const ScheduleOutcome outcome =
      simulate_schedule(work, threads, schedule, MachineCosts::tests_only());
  std::vector<std::uint64_t> tests;
  tests.reserve(outcome.threads.size());
  for (const ThreadShare& share : outcome.threads) tests.push_back(share.tests);
  return tests;
}

double imbalance(std::span<const double> per_thread) {
  if (per_thread.empty()) return 0.0;
  double max = 0.0, sum = 0.0;
  for (const double load : per_thread) {
    max = std::max(max, load);
    sum += load;
  }
  if (max <= 0.0) return 0.0;
  const double mean = sum / static_cast<double>(per_thread.size());
  return (max - mean) / max;
}

double imbalance(std::span<const std::uint64_t> per_thread) {
  std::vector<double> loads(per_thread.begin(), per_thread.end());
  return imbalance(std::span<const double>(loads));
}

std::vector<int> log2_chunk_grid(int largest_chunk) {
  if (largest_chunk < 1) {
    throw std::invalid_argument(
        "log2_chunk_grid: largest_chunk = " + std::to_string(largest_chunk) + " must be >= 1");
  }
  std::vector<int> grid;
  for (long long k = 1; k <= largest_chunk; k *= 2) grid.push_back(static_cast<int>(k));
  return grid;
}

std::vector<int> balanced_chunk_grid(std::span<const int> grid, std::size_t iterations,
                                     int threads) {
  const std::uint64_t largest = iterations / (std::uint64_t{kMinChunksPerThread} *
                                              static_cast<std::uint64_t>(std::max(1, threads)));
  std::vector<int> kept;
  for (const int chunk : grid) {
    if (static_cast<std::uint64_t>(chunk) <= largest) kept.push_back(chunk);
  }
  if (kept.empty() && !grid.empty()) kept.push_back(*std::min_element(grid.begin(), grid.end()));
  return kept;
}

ChunkPrediction predict_best_chunk(WorkView work, int threads, ScheduleKind kind,
                                   const MachineCosts& costs,
                                   std::span<const int> candidate_chunks) {
  return predict_best_chunk(PreparedWork(work), threads, kind, costs, candidate_chunks);
}

ChunkPrediction predict_best_chunk(const PreparedWork& work, int threads, ScheduleKind kind,
                                   const MachineCosts& costs,
                                   std::span<const int> candidate_chunks) {
  check_threads("predict_best_chunk", threads);
  if (candidate_chunks.empty()) {
    throw std::invalid_argument("predict_best_chunk: no candidate chunks");
  }
  for (const int chunk : candidate_chunks) check_schedule("predict_best_chunk", {kind, chunk});
  ChunkPrediction prediction;
  for (const int chunk : candidate_chunks) {
    const ScheduleOutcome outcome = simulate_schedule(work, threads, {kind, chunk}, costs);
    prediction.candidates.push_back({chunk, outcome.makespan_seconds, outcome.imbalance,
                                     outcome.max_thread_tests, outcome.total_chunks});
  }
  // Block (chunk 0) counts as the largest chunk of all: one contiguous run per thread.
  auto locality_rank = [](int chunk) {
    return chunk == 0 ? std::numeric_limits<long long>::max() : static_cast<long long>(chunk);
  };
  const CandidatePrediction* best = &prediction.candidates.front();
  for (const CandidatePrediction& candidate : prediction.candidates) {
    if (candidate.predicted_seconds < best->predicted_seconds ||
        (candidate.predicted_seconds == best->predicted_seconds &&
         locality_rank(candidate.chunk) > locality_rank(best->chunk))) {
      best = &candidate;
    }
  }
  prediction.best_chunk = best->chunk;
  prediction.best_seconds = best->predicted_seconds;
  return prediction;
}

}  // namespace contactlab::tuner
