// A filter or an expansion on a team of threads whose output keeps the input's order: each
// thread counts the outputs of its range of the input, the counts are summed over the ranges
// before it, and each thread writes its range's outputs from there. The output is the same for
// any team size (the order a loop over the input on one thread gives), and no pass over the
// input or the output runs on one thread.
#pragma once

#include <omp.h>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace contactlab {

// `count(first, last)`: how many outputs the input range [first, last) gives.
// `size(total)`: called once, on one thread, after every count and before any fill (the place
// to size the outputs).
// `fill(first, last, at)`: writes the outputs of [first, last) from output index `at`.
template <class Count, class Size, class Fill>
void count_then_fill(std::size_t n, int threads, Count&& count, Size&& size, Fill&& fill) {
  std::vector<std::size_t> range_start(static_cast<std::size_t>(threads) + 1, 0);
#pragma omp parallel num_threads(threads)
  {
    const auto t = static_cast<std::size_t>(omp_get_thread_num());
    const auto team = static_cast<std::size_t>(omp_get_num_threads());
    const std::size_t first = n * t / team, last = n * (t + 1) / team;
    range_start[t + 1] = count(first, last);
#pragma omp barrier
#pragma omp single
    {
      for (std::size_t u = 0; u < team; ++u) range_start[u + 1] += range_start[u];
      size(range_start[team]);
    }  // implicit barrier
    fill(first, last, range_start[t]);
  }
}

// values[0..n) replaced by their running sums on `threads` threads: each sums an equal range,
// then adds the sums of the ranges before it (range_sums: its scratch, one entry a thread).
inline void parallel_inclusive_scan(std::uint64_t* values, std::size_t n, int threads,
                                    std::vector<std::uint64_t>& range_sums) {
  range_sums.assign(static_cast<std::size_t>(threads), 0);
#pragma omp parallel num_threads(threads)
  {
    const auto t = static_cast<std::size_t>(omp_get_thread_num());
    const auto team = static_cast<std::size_t>(omp_get_num_threads());
    const std::size_t first = n * t / team, last = n * (t + 1) / team;
    std::uint64_t running = 0;
    for (std::size_t k = first; k < last; ++k) running = values[k] += running;
    range_sums[t] = running;
#pragma omp barrier
    std::uint64_t base = 0;
    for (std::size_t u = 0; u < t; ++u) base += range_sums[u];
    if (base > 0) {
      for (std::size_t k = first; k < last; ++k) values[k] += base;
    }
  }
}

}  // namespace contactlab
