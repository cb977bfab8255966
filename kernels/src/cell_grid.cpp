#include "contactlab/kernels/cell_grid.hpp"

#include <algorithm>
#include <string>

#include "contactlab/kernels/error.hpp"

namespace contactlab {

CellGrid::CellGrid(const Box& box, double min_width, CellNumbering numbering)
    : numbering_(numbering) {
  if (!(min_width > 0.0) || !std::isfinite(min_width)) {
    throw InputError("cell width (diameter D) must be a positive finite number, got " +
                     std::to_string(min_width));
  }
  const double width = min_width * (1.0 + 0x1.0p-40);
  std::uint64_t cells = 1;
  for (int axis = 0; axis < 3; ++axis) {
    const double extent = box.extent(axis);
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

void CellRegistry::assign(const CellGrid& grid, const Scene& scene) {
  const std::size_t n = scene.size();
  const std::uint64_t keys = grid.key_count();
  // Counting sort: counts land two places up so that, after the prefix sum, cell_begin[k + 1]
  // is the start of cell k and serves as its fill cursor; once filled it holds the end of k,
  // which is the start of k + 1, leaving cell_begin[k] = start of k.
  cell_begin.assign(keys + 2, 0);
  particle_key.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const auto c = grid.coords_of(scene.x[i], scene.y[i], scene.z[i]);
    const std::uint32_t key = grid.key(c[0], c[1], c[2]);
    particle_key[i] = key;
    ++cell_begin[key + 2];
  }
  std::uint32_t largest = 0;
  std::uint32_t running = 0;
  for (std::uint64_t k = 2; k < keys + 2; ++k) {
    largest = std::max(largest, cell_begin[k]);
    running += cell_begin[k];
    cell_begin[k] = running;
  }
  max_occupancy = largest;
  slot_particle.resize(n);
  particle_slot.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t slot = cell_begin[particle_key[i] + 1]++;
    slot_particle[slot] = static_cast<std::uint32_t>(i);
    particle_slot[i] = slot;
  }
  cell_begin.resize(keys + 1);
}

}  // namespace contactlab
