#include "contactlab/kernels/cell_grid.hpp"

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

void CellRegistry::assign(const CellGrid& grid, const Scene& scene, Scene* sorted) {
  const std::size_t n = scene.size();
  const std::uint64_t keys = grid.key_count();
  // Sort (key, input index) pairs by key with a stable LSD radix sort. A counting sort over
  // the cell table would touch the (up to 2^28-entry) table at random once per particle; the
  // radix passes keep their 2^kDigitBits counters in L1 and write in sequential streams.
  constexpr int kDigitBits = 12;
  constexpr std::uint64_t kBuckets = std::uint64_t{1} << kDigitBits;
  int key_bits = 1;
  while ((std::uint64_t{1} << key_bits) < keys) ++key_bits;
  const int passes = (key_bits + kDigitBits - 1) / kDigitBits;

  sort_buffer_.resize(n);
  sort_scratch_.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const auto c = grid.coords_of(scene.x[i], scene.y[i], scene.z[i]);
    sort_buffer_[i] = (std::uint64_t{grid.key(c[0], c[1], c[2])} << 32) | i;
  }
  std::vector<std::uint64_t> histogram(kBuckets);
  for (int pass = 0; pass < passes; ++pass) {
    const int shift = 32 + pass * kDigitBits;
    std::fill(histogram.begin(), histogram.end(), 0);
    for (const std::uint64_t entry : sort_buffer_) ++histogram[(entry >> shift) & (kBuckets - 1)];
    std::uint64_t running = 0;
    for (auto& h : histogram) running += std::exchange(h, running);
    for (const std::uint64_t entry : sort_buffer_) {
      sort_scratch_[histogram[(entry >> shift) & (kBuckets - 1)]++] = entry;
    }
    sort_buffer_.swap(sort_scratch_);
  }

  // Slots in key order; cell_begin[k] = first slot whose key is >= k.
  slot_particle.resize(n);
  cell_begin.resize(keys + 1);
  std::uint64_t next_key = 0;  // cell_begin is filled for every key below next_key
  std::uint32_t largest = 0, run_start = 0;
  for (std::uint32_t s = 0; s < n; ++s) {
    const std::uint64_t entry = sort_buffer_[s];
    const std::uint64_t slot_key = entry >> 32;
    slot_particle[s] = static_cast<std::uint32_t>(entry);
    if (slot_key >= next_key) {  // the first slot of a new cell
      largest = std::max(largest, s - run_start);
      run_start = s;
      while (next_key <= slot_key) cell_begin[next_key++] = s;
    }
  }
  largest = std::max(largest, static_cast<std::uint32_t>(n) - run_start);
  while (next_key <= keys) cell_begin[next_key++] = static_cast<std::uint32_t>(n);
  max_occupancy = largest;

  if (sorted) {
    // The paper's reordering: coordinates copied into slot order.
    sorted->box = scene.box;
    sorted->x.resize(n);
    sorted->y.resize(n);
    sorted->z.resize(n);
    sorted->diameter.resize(scene.diameter.size());
    const bool diameters = scene.has_diameters();
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
    for (std::uint32_t s = 0; s < n; ++s) particle_slot[slot_particle[s]] = s;
  }
}

}  // namespace contactlab
