// The balanced schedule's blocks: the iterations 0..m-1 cut into one consecutive block per
// thread of a parallel region, block t beginning at the first iteration whose prefix of weights
// reaches t / P of the total (the weights are what an iteration is expected to cost).
//
// Called by every thread of the region (it holds two barriers), each thread gets its own block.
// Each thread weighs an equal slice of the iterations (keeping the slice's weights), the
// slices' sums are scanned, and each thread finds the bounds that fall in its slice: O(m / P + P)
// per thread, each weight found once, m / P weights kept per thread. (LB4OMP's static_steal
// balances while it runs; here a home's pair tests are known from its stencil's cells before
// the loop, and the blocks keep the block schedule's rows: a thread's homes stay one run of
// consecutive rows.)
#pragma once

#include <omp.h>

#include <cstdint>
#include <vector>

namespace contactlab {

// A home's fixed cost (its block of the SIMD test, its stencil's rows and their masked tails,
// its output) in pair tests, beside its tests: what the balanced schedule weighs a home by, in
// the detector and in the schedule model. Measured as the calibration's per-home over per-test
// seconds (s_iter / s_test of the sorted particle loop, s_home / s_test of the cell loop): 160 -
// 280 on the AVX-512 Turin-like VM in three calibrations (a test is an eighth of a vector
// instruction's work there, a home a few hundred cycles). At 16 (its first value) the blocks
// balanced the tests and not the time: the threads of the sparse outskirts took most of the
// homes, and the model emulated `particle/sorted/full/balanced` at 17.0 ms of T_c at 16
// threads, slower than the block's 13.3; at 200, 9.3 ms (the paper scene, 2026-12-05).
inline constexpr std::uint64_t kHomeTests = 200;

struct IterationBlock {
  std::uint64_t begin = 0, end = 0;
};

// Shared by the region's threads: the slices' sums and the block bounds (2 P + 1 entries).
class BalancedBlocks {
 public:
  // Before the region: room for `threads` threads.
  void prepare(int threads) {
    weigh_seconds_ = 0.0;
    scratch_.assign(2 * static_cast<std::size_t>(threads) + 1, 0);
    if (slice_weights_.size() < static_cast<std::size_t>(threads)) slice_weights_.resize(threads);
  }

  // This thread's block of iterations [0, m) under weights weight_of(k) >= 1.
  template <class WeightOf>
  IterationBlock block(std::uint64_t m, WeightOf weight_of) {
    const int threads = omp_get_num_threads();
    if (threads == 1) return {0, m};
    const double start = omp_get_wtime();
    const auto tid = static_cast<std::size_t>(omp_get_thread_num());
    const auto p = static_cast<std::size_t>(threads);
    std::uint64_t* const sums = scratch_.data();
    std::uint64_t* const bounds = scratch_.data() + p;  // bounds[t]: block t's first iteration
    const std::uint64_t first = m * tid / p, last = m * (tid + 1) / p;
    // Each weight is found once (a stencil build per cell): kept for the second pass.
    std::vector<std::uint64_t>& weights = slice_weights_[tid];
    weights.resize(last - first);
    std::uint64_t sum = 0;
    for (std::uint64_t k = first; k < last; ++k) sum += weights[k - first] = weight_of(k);
    sums[tid] = sum;
#pragma omp barrier
    // Every slice is weighed here: thread 0's clock holds the slowest weighing.
    if (tid == 0) weigh_seconds_ = omp_get_wtime() - start;
    std::uint64_t base = 0, total = 0;
    for (std::size_t t = 0; t < p; ++t) {
      if (t < tid) base += sums[t];
      total += sums[t];
    }
    // Block t (t >= 1) begins after the first iteration at whose end the prefix reaches
    // target(t); this slice holds the targets in (base, base + sum].
    auto target = [&](std::size_t t) { return total / p * t + total % p * t / p; };
    std::size_t t = 1;
    while (t < p && target(t) <= base) ++t;
    if (tid == 0) {
      bounds[0] = 0;
      bounds[p] = m;
      // A total of 0 (no iterations) puts every bound at 0.
      for (std::size_t u = 1; u < t; ++u) bounds[u] = 0;
    }
    std::uint64_t running = base;
    for (std::uint64_t k = first; k < last && t < p && target(t) <= base + sum; ++k) {
      running += weights[k - first];
      while (t < p && target(t) <= running) bounds[t++] = k + 1;
    }
#pragma omp barrier
    return {bounds[tid], bounds[tid + 1]};
  }

  // The last region's weighing: seconds until every thread had weighed its slice (0 at one
  // thread, which does not weigh).
  double weigh_seconds() const { return weigh_seconds_; }

 private:
  double weigh_seconds_ = 0.0;
  std::vector<std::uint64_t> scratch_;
  std::vector<std::vector<std::uint64_t>> slice_weights_;  // per thread: its slice's weights
};

}  // namespace contactlab
