#include "contactlab/dem/row_ranges.hpp"

#include <algorithm>
#include <atomic>
#include <numeric>
#include <thread>

namespace contactlab::dem {

namespace {

// The multiple of kAlign in [lo, n] (or n itself) whose work before it is nearest `target`:
// a binary search, the work rising with a.
std::size_t start_near(std::span<const std::uint32_t> rows, std::size_t n, std::size_t lo,
                       double target) {
  constexpr std::size_t kAlign = RowRanges::kAlign;
  std::size_t low = lo / kAlign, high = n / kAlign;  // in groups of kAlign
  while (low < high) {  // the first group start whose work reaches the target
    const std::size_t mid = low + (high - low) / 2;
    if (static_cast<double>(work_before(rows, mid * kAlign)) < target) {
      low = mid + 1;
    } else {
      high = mid;
    }
  }
  std::size_t a = low * kAlign;
  if (a > lo && a - kAlign >= lo &&
      target - static_cast<double>(work_before(rows, a - kAlign)) <
          static_cast<double>(work_before(rows, a)) - target) {
    a -= kAlign;  // the group start below is nearer
  }
  return std::max(lo, std::min(a, n));
}

}  // namespace

std::span<const std::size_t> RowRanges::plan(std::span<const std::uint32_t> rows, std::size_t n,
                                             std::size_t threads) {
  if (rows.size() != n + 1) rows = {};  // not the particles' list (none yet): their count only
  if (rate_.size() != threads) {        // a new team: nothing known of its threads
    rate_.assign(threads, 0.0);
    busy_.assign(threads, 0.0);
  }
  // Each thread's share of the work: in proportion to its speed (1 / seconds per unit), the
  // threads not yet measured at the mean speed of those that were.
  std::vector<double>& speed = speed_;  // kept: no allocation per step
  speed.assign(threads, 0.0);
  double known = 0.0;
  std::size_t measured = 0;
  for (std::size_t t = 0; t < threads; ++t) {
    if (rate_[t] > 0.0) {
      speed[t] = 1.0 / rate_[t];
      known += speed[t];
      ++measured;
    }
  }
  const double fallback = measured > 0 ? known / static_cast<double>(measured) : 1.0;
  for (double& s : speed) s = s > 0.0 ? s : fallback;
  const double total_speed = std::accumulate(speed.begin(), speed.end(), 0.0);
  const auto total_work = static_cast<double>(work_before(rows, n));
  bounds_.assign(threads + 1, n);
  bounds_[0] = 0;
  double before = 0.0;
  for (std::size_t t = 1; t < threads; ++t) {
    before += speed[t - 1];
    bounds_[t] = start_near(rows, n, bounds_[t - 1], total_work * before / total_speed);
  }
  std::fill(busy_.begin(), busy_.end(), 0.0);
  return bounds_;
}

void RowRanges::record(std::size_t t, double busy_s) { busy_[t] = busy_s; }

void RowRanges::learn(std::span<const std::uint32_t> rows) {
  if (bounds_.empty()) return;
  if (rows.size() != bounds_.back() + 1) rows = {};  // as plan counted them
  for (std::size_t t = 0; t + 1 < bounds_.size(); ++t) {
    const std::uint64_t work = work_before(rows, bounds_[t + 1]) - work_before(rows, bounds_[t]);
    if (work == 0 || !(busy_[t] > 0.0)) continue;  // nothing to learn from an empty range
    const double seen = busy_[t] / static_cast<double>(work);
    // One step's reading moves the rate by at most a factor of two: a preempted step (a
    // millisecond of the host's) should not hand half the work to the other threads.
    double& rate = rate_[t];
    rate = rate > 0.0
               ? (1.0 - kSmoothing) * rate + kSmoothing * std::clamp(seen, 0.5 * rate, 2.0 * rate)
               : seen;
  }
}

void RowsDone::resize(std::size_t threads) {
  if (signals_.size() < kStride * threads) signals_.resize(kStride * threads, 0);
}

void RowsDone::announce(std::size_t t, std::uint64_t pass) {
  std::atomic_ref<std::uint64_t>(signals_[kStride * t]).store(pass, std::memory_order_release);
}

void RowsDone::wait_for(std::size_t u, std::uint64_t pass) {
  const std::atomic_ref<std::uint64_t> signal(signals_[kStride * u]);
  for (unsigned spins = 0; signal.load(std::memory_order_acquire) < pass; ++spins) {
    if (spins < 4096) {
#if defined(__x86_64__) || defined(__i386__)
      __builtin_ia32_pause();
#endif
    } else {
      std::this_thread::yield();
    }
  }
}

}  // namespace contactlab::dem
