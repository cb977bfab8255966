// The contact-detection cell grid and the registration of particles in it (counting sort).
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "contactlab/kernels/large_vector.hpp"
#include "contactlab/kernels/scene.hpp"

namespace contactlab {

// How cells are numbered, which is also the order in which sorted particles are stored.
enum class CellNumbering { kLinear, kMorton };

class CellGrid {
 public:
  // Cells per axis G = max(1, floor(L / w)) with w = min_width (1 + e), e = max(2^-40,
  // 2^-46 (L / D + max|coordinate| / D)). The small widening keeps the 27-cell search exact:
  // with w exactly D (D = 1/200 in a unit box), rounding in floor(x / w) could put two
  // particles at distance D two cells apart; the error grows with the cell count and the
  // distance of the box from the origin, and so does e. Throws InputError if min_width <= 0
  // or the grid would need more than kMaxKeys keys (Morton keys: 2^(3 b) for 2^b >= the
  // largest G, so Morton numbering allows at most 512 cells per axis).
  CellGrid(const Box& box, double min_width, CellNumbering numbering);

  static constexpr std::uint64_t kMaxKeys = std::uint64_t{1} << 28;

  const std::array<int, 3>& dims() const { return dims_; }
  const std::array<double, 3>& cell_width() const { return width_; }
  CellNumbering numbering() const { return numbering_; }
  // Keys run over [0, key_count()); with Morton numbering some keys are not cells.
  std::uint64_t key_count() const { return key_count_; }
  std::uint64_t cell_count() const {
    return std::uint64_t(dims_[0]) * std::uint64_t(dims_[1]) * std::uint64_t(dims_[2]);
  }

  // The cell holding a point; points on the box's upper faces belong to the last cell.
  std::array<int, 3> coords_of(double x, double y, double z) const {
    return {axis_coord(0, x), axis_coord(1, y), axis_coord(2, z)};
  }
  bool in_range(int cx, int cy, int cz) const {
    return cx >= 0 && cy >= 0 && cz >= 0 && cx < dims_[0] && cy < dims_[1] && cz < dims_[2];
  }
  std::uint32_t key(int cx, int cy, int cz) const {
    if (numbering_ == CellNumbering::kLinear) {
      return static_cast<std::uint32_t>((cz * dims_[1] + cy) * dims_[0] + cx);
    }
    return morton_part(0, cx) | morton_part(1, cy) | morton_part(2, cz);
  }
  // A Morton key is the OR of one part per axis, so a stencil row computes its y and z parts
  // once and each cell adds its x part (the bit interleave is most of a key's cost).
  static std::uint32_t morton_part(int axis, int c) { return spread_bits(c) << axis; }

 private:
  int axis_coord(int axis, double v) const {
    const double scaled = (v - lo_[axis]) * inverse_width_[axis];
    int c = static_cast<int>(scaled);  // scaled >= 0 for points inside the box
    return c < dims_[axis] ? c : dims_[axis] - 1;
  }
  // Inserts two zero bits between consecutive bits of a 10-bit value (Morton interleave).
  static std::uint32_t spread_bits(int v) {
    std::uint32_t x = static_cast<std::uint32_t>(v) & 0x3ffu;
    x = (x | (x << 16)) & 0x030000ffu;
    x = (x | (x << 8)) & 0x0300f00fu;
    x = (x | (x << 4)) & 0x030c30c3u;
    x = (x | (x << 2)) & 0x09249249u;
    return x;
  }

  std::array<int, 3> dims_{1, 1, 1};
  std::array<double, 3> lo_{}, width_{}, inverse_width_{};
  CellNumbering numbering_ = CellNumbering::kLinear;
  std::uint64_t key_count_ = 1;
};

// Coordinates (and diameters, where the scene has them) in slot order: the paper's reordering.
// LargeVectors: filled, and their pages first touched, by the registering threads.
struct SortedCoordinates {
  LargeVector<double> x, y, z, diameter;
  std::size_t size() const { return x.size(); }
};

// Particles registered in cells (sorted by cell key, stably): the particles of the cell with key k
// occupy slots [cell_begin[k], cell_begin[k + 1]), and slot s holds input particle
// slot_particle[s].
struct CellRegistry {
  LargeVector<std::uint32_t> cell_begin;     // key_count + 1 entries
  LargeVector<std::uint32_t> slot_particle;  // slot -> input index
  LargeVector<std::uint32_t> particle_slot;  // input index -> slot
  std::uint32_t max_occupancy = 0;
  // Sum over cells of occupancy^2: divided by the particle count, the mean occupancy of a
  // particle's own cell (itself included), what a particle's stencil holds per cell.
  std::uint64_t occupancy_squares = 0;

  // Registers the particles. With `sorted`, also copies the coordinates (and diameters) into
  // slot order: the paper's reordering. particle_slot is filled only without it (the
  // unsorted layout needs it; sorted ones use slots as ids). Runs on `threads` threads (keys,
  // the radix sort's passes, the cell table, the reordering); the result is the same for any
  // thread count.
  void assign(const CellGrid& grid, const Scene& scene, SortedCoordinates* sorted = nullptr,
              int threads = 1);

 private:
  LargeVector<std::uint64_t> sort_buffer_, sort_scratch_;  // (key << 32 | index) pairs
  std::vector<std::uint64_t> histograms_;                  // per thread, the radix digit counts
};

}  // namespace contactlab
