#include "contactlab/kernels/cell_grid.hpp"

#include <omp.h>

#include <algorithm>
#include <string>
#include <utility>

#include "contactlab/kernels/error.hpp"

namespace contactlab {

CellGrid::CellGrid(const Box& box, double min_width, CellNumbering numbering)
    : numbering_(numbering) {
  if (!(min_width > 0.0) || !std::isfinite(min_width)) {
    throw InputError("cell width (diameter D) must be a positive finite number, got " +
                     std::to_string(min_width));
  }
  std::uint64_t cells = 1;
  for (int axis = 0; axis < 3; ++axis) {
    const double extent = box.extent(axis);
    // Widen the cell a little beyond D so that two particles at distance D (give or take the
    // rounding of the contact test) can never be found two cells apart: the cell coordinate
    // floor((x - lo) / w) carries a rounding error of a few ulps of (x - lo) / w and of
    // |x| / w, so the widening grows with the cell count and the distance from the origin.
    const double cells_estimate = extent / min_width;
    const double origin_scale =
        std::max(std::abs(box.lo[axis]), std::abs(box.hi[axis])) / min_width;
    const double widening = std::max(0x1.0p-40, 0x1.0p-46 * (cells_estimate + origin_scale));
    const double width = min_width * (1.0 + widening);
    const double per_axis = std::floor(extent / width);
    if (per_axis > double(kMaxKeys)) {
      throw InputError("cell grid too large: D = " + std::to_string(min_width) +
                       " is too small for the box (more than 2^28 cells)");
    }
    dims_[axis] = std::max(1, static_cast<int>(per_axis));
    cells *= std::uint64_t(dims_[axis]);
    lo_[axis] = box.lo[axis];
    width_[axis] = extent / dims_[axis];
    inverse_width_[axis] = dims_[axis] / extent;
  }
  if (numbering == CellNumbering::kLinear) {
    key_count_ = cells;
  } else {
    const int largest = std::max({dims_[0], dims_[1], dims_[2]});
    int bits = 0;
    while ((1 << bits) < largest) ++bits;
    key_count_ = std::uint64_t{1} << (3 * bits);
  }
  if (key_count_ > kMaxKeys) {
    throw InputError("cell grid too large: " + std::to_string(dims_[0]) + "x" +
                     std::to_string(dims_[1]) + "x" + std::to_string(dims_[2]) +
                     " cells exceed 2^28 keys (D = " + std::to_string(min_width) +
                     " is too small for the box)");
  }
}

void CellRegistry::assign(const CellGrid& grid, const Scene& scene, SortedCoordinates* sorted,
                          int threads) {
  const std::size_t n = scene.size();
  const std::uint64_t keys = grid.key_count();
  // Sort (key, input index) pairs by key with a stable LSD radix sort. A counting sort over
  // the cell table would touch the (up to 2^28-entry) table at random once per particle; the
  // radix passes keep their 2^kDigitBits counters in L1 and write in sequential streams.
  // In parallel: each thread counts its contiguous range of the input, the ranges' offsets
  // are laid out bucket by bucket in thread order (so the sort stays stable and the result is
  // the same for any thread count), and each thread scatters its range.
  constexpr int kDigitBits = 12;
  constexpr std::size_t kBuckets = std::size_t{1} << kDigitBits;
  int key_bits = 1;
  while ((std::uint64_t{1} << key_bits) < keys) ++key_bits;
  const int passes = (key_bits + kDigitBits - 1) / kDigitBits;
  const auto team = static_cast<std::size_t>(std::max(1, threads));

  sort_buffer_.resize(n);
  sort_scratch_.resize(n);
  slot_particle.resize(n);
  cell_begin.resize(keys + 1);
  histograms_.assign(team * kBuckets, 0);
  std::uint32_t largest = 0;
  std::uint64_t* from = sort_buffer_.data();
  std::uint64_t* to = sort_scratch_.data();
  std::uint64_t squares = 0;
#pragma omp parallel num_threads(static_cast <int>(team)) reduction(max : largest) \
    reduction(+ : squares)
  {
    const auto t = static_cast<std::size_t>(omp_get_thread_num());
    const std::size_t size = static_cast<std::size_t>(omp_get_num_threads());
    const std::size_t b = n * t / size, e = n * (t + 1) / size;
    for (std::size_t i = b; i < e; ++i) {
      const auto c = grid.coords_of(scene.x[i], scene.y[i], scene.z[i]);
      from[i] = (std::uint64_t{grid.key(c[0], c[1], c[2])} << 32) | i;
    }
    std::uint64_t* mine = histograms_.data() + t * kBuckets;
    std::uint64_t* in = from;
    std::uint64_t* out = to;
    for (int pass = 0; pass < passes; ++pass) {
      const int shift = 32 + pass * kDigitBits;
      std::fill(mine, mine + kBuckets, 0);
      for (std::size_t i = b; i < e; ++i) ++mine[(in[i] >> shift) & (kBuckets - 1)];
#pragma omp barrier
#pragma omp single
      {  // offsets: bucket by bucket, within a bucket thread by thread
        std::uint64_t running = 0;
        for (std::size_t bucket = 0; bucket < kBuckets; ++bucket) {
          for (std::size_t u = 0; u < size; ++u) {
            running += std::exchange(histograms_[u * kBuckets + bucket], running);
          }
        }
      }  // implicit barrier
      for (std::size_t i = b; i < e; ++i) out[mine[(in[i] >> shift) & (kBuckets - 1)]++] = in[i];
      std::swap(in, out);
#pragma omp barrier
    }
    // Slots in key order; cell_begin[k] = first slot whose key is >= k. Each thread fills the
    // keys from the one before its range's first new cell up to its last: disjoint ranges.
    for (std::size_t s = b; s < e; ++s) {
      const std::uint64_t entry = in[s];
      const std::uint64_t slot_key = entry >> 32;
      slot_particle[s] = static_cast<std::uint32_t>(entry);
      const std::uint64_t previous = s == 0 ? 0 : (in[s - 1] >> 32) + 1;
      if (s > 0 && slot_key + 1 == previous) continue;  // same cell as the slot before
      for (std::uint64_t k = previous; k <= slot_key; ++k) {
        cell_begin[k] = static_cast<std::uint32_t>(s);
      }
      std::size_t end = s + 1;  // the cell's run, possibly into the next thread's range
      while (end < n && (in[end] >> 32) == slot_key) ++end;
      largest = std::max(largest, static_cast<std::uint32_t>(end - s));
      squares += std::uint64_t{end - s} * (end - s);
    }
    if (t + 1 == size) {  // the keys past the last particle's (all of them when there is none)
      const std::uint64_t after = n == 0 ? 0 : (in[n - 1] >> 32) + 1;
      for (std::uint64_t k = after; k <= keys; ++k) cell_begin[k] = static_cast<std::uint32_t>(n);
    }
  }
  if (passes % 2 == 1) sort_buffer_.swap(sort_scratch_);  // the sorted entries' vector first
  max_occupancy = largest;
  occupancy_squares = squares;

  if (sorted) {
    // The paper's reordering: coordinates copied into slot order.
    sorted->x.resize(n);
    sorted->y.resize(n);
    sorted->z.resize(n);
    sorted->diameter.resize(scene.diameter.size());
    const bool diameters = scene.has_diameters();
#pragma omp parallel for schedule(static) num_threads(static_cast <int>(team))
    for (std::size_t s = 0; s < n; ++s) {
      const std::uint32_t i = slot_particle[s];
      sorted->x[s] = scene.x[i];
      sorted->y[s] = scene.y[i];
      sorted->z[s] = scene.z[i];
      if (diameters) sorted->diameter[s] = scene.diameter[i];
    }
    particle_slot.clear();
  } else {
    particle_slot.resize(n);
#pragma omp parallel for schedule(static) num_threads(static_cast <int>(team))
    for (std::size_t s = 0; s < n; ++s)
      particle_slot[slot_particle[s]] = static_cast<std::uint32_t>(s);
  }
}

}  // namespace contactlab
