// The contact-detection cell grid and the registration of particles in it (counting sort).
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "contactlab/kernels/large_vector.hpp"
#include "contactlab/kernels/scene.hpp"
#include "contactlab/kernels/variant.hpp"

namespace contactlab {

// How cells are numbered, which is also the order in which sorted particles are stored.
enum class CellNumbering { kLinear, kMorton };

class CellGrid {
 public:
  // Cells per axis G = max(1, floor(L / w)) with w = min_width (1 + e), e = max(2^-40,
  // 2^-46 (L / D + max|coordinate| / D)). The small widening keeps the 27-cell search exact:
  // with w exactly D (D = 1/200 in a unit box), rounding in floor(x / w) could put two
  // particles at distance D two cells apart; the error grows with the cell count and the
  // distance of the box from the origin, and so does e. It stays far below a cell for every
  // grid allowed here: at kMaxAxisCells = 2^30 cells on an axis e is about 2^-16, while the
  // rounding it covers is a few ulps of G, i.e. about 2^-22 of a cell. Throws InputError if
  // min_width <= 0, an axis would hold more than kMaxAxisCells cells, the linear keys would
  // not fit in 62 bits, or (Morton numbering) an axis would hold more than 2^21 cells (keys of
  // 3 x 21 interleaved bits). Grids of more than kMaxKeys keys are indexed by their occupied
  // cells only (GridIndex::kHashed, see use_hashed_index).
  CellGrid(const Box& box, double min_width, CellNumbering numbering);

  // The most keys a dense cell table (one entry per key) may have: 1 GiB of 32-bit entries.
  static constexpr std::uint64_t kMaxKeys = std::uint64_t{1} << 28;
  static constexpr int kMaxAxisCells = 1 << 30;
  static constexpr int kMaxMortonAxisCells = 1 << 21;

  const std::array<int, 3>& dims() const { return dims_; }
  const std::array<double, 3>& cell_width() const { return width_; }
  CellNumbering numbering() const { return numbering_; }
  // Keys run over [0, key_count()); with Morton numbering some keys are not cells.
  std::uint64_t key_count() const { return key_count_; }
  // Whether a dense cell table (GridIndex::kDense) can index the grid.
  bool dense_fits() const { return key_count_ <= kMaxKeys; }
  std::uint64_t cell_count() const {
    return std::uint64_t(dims_[0]) * std::uint64_t(dims_[1]) * std::uint64_t(dims_[2]);
  }

  // The cell holding a point; points on the box's upper faces belong to the last cell. Always
  // inlined: as a call (GCC's choice at -O3) it returned the three coordinates through the stack,
  // a load waiting on two narrower stores, 4 % of the paper scene's T_ALL at one thread.
  [[gnu::always_inline]] std::array<int, 3> coords_of(double x, double y, double z) const {
    return {axis_coord(0, x), axis_coord(1, y), axis_coord(2, z)};
  }
  bool in_range(int cx, int cy, int cz) const {
    return cx >= 0 && cy >= 0 && cz >= 0 && cx < dims_[0] && cy < dims_[1] && cz < dims_[2];
  }
  // The key of a cell of a grid that dense_fits() (32 bits: the dense table's index).
  std::uint32_t key(int cx, int cy, int cz) const {
    if (numbering_ == CellNumbering::kLinear) {
      return static_cast<std::uint32_t>((cz * dims_[1] + cy) * dims_[0] + cx);
    }
    return morton_part(0, cx) | morton_part(1, cy) | morton_part(2, cz);
  }
  // The wide_key() of the cells holding points 0..count-1 of x, y, z (the key() of a grid that
  // dense_fits()), into keys. One loop without the histogram's scattered increments: the
  // compiler runs it on SIMD lanes, where a key per call of coords_of() and wide_key() was a
  // tenth of the registration.
  void keys_of(const double* x, const double* y, const double* z, std::size_t count,
               std::uint64_t* keys) const;

  // A Morton key is the OR of one part per axis, so a stencil row computes its y and z parts
  // once and each cell adds its x part (the bit interleave is most of a key's cost).
  static std::uint32_t morton_part(int axis, int c) { return spread_bits(c) << axis; }

  // The key of a cell of any grid (64 bits: the hashed index's). The same as key() where that
  // is defined, so both indexes order the slots the same way.
  std::uint64_t wide_key(int cx, int cy, int cz) const {
    if (numbering_ == CellNumbering::kLinear) {
      return (std::uint64_t(cz) * std::uint64_t(dims_[1]) + std::uint64_t(cy)) *
                 std::uint64_t(dims_[0]) +
             std::uint64_t(cx);
    }
    return wide_morton_part(0, cx) | wide_morton_part(1, cy) | wide_morton_part(2, cz);
  }
  static std::uint64_t wide_morton_part(int axis, int c) { return spread_bits_wide(c) << axis; }

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
  // The same for a 21-bit value.
  static std::uint64_t spread_bits_wide(int v) {
    std::uint64_t x = static_cast<std::uint64_t>(v) & 0x1fffffu;
    x = (x | (x << 32)) & 0x1f00000000ffffull;
    x = (x | (x << 16)) & 0x1f0000ff0000ffull;
    x = (x | (x << 8)) & 0x100f00f00f00f00full;
    x = (x | (x << 4)) & 0x10c30c30c30c30c3ull;
    x = (x | (x << 2)) & 0x1249249249249249ull;
    return x;
  }

  std::array<int, 3> dims_{1, 1, 1};
  std::array<double, 3> lo_{}, width_{}, inverse_width_{};
  CellNumbering numbering_ = CellNumbering::kLinear;
  std::uint64_t key_count_ = 1;
};

// Whether a scene's coordinate arrays are large enough that reading them at random pays for a
// copy first (the reordering's staged records; the unsorted loops' copy in huge pages): from
// kCopyForRandomReadsFrom bytes of arrays. The scene's std::vector arrays lie in 4 KiB pages and
// the copies in huge pages written as a stream; on the 2-core Xeon VM (clustered, D = 1/200,
// 2026-12-07) the copies made T_ALL 0.91 - 0.94 of the direct reads at 1,024,000 particles
// (24 MB of arrays), 0.93 - 1.01 at 300,000 (7.2 MB) and 1.00 - 1.10 at 100,000 (2.4 MB: a
// few MB that L2, L3 and the TLB's reach hold).
inline constexpr std::size_t kCopyForRandomReadsFrom = std::size_t{4} << 20;  // bytes
bool copy_for_random_reads(const Scene& scene);

// Coordinates (and diameters, where the scene has them) in slot order: the paper's reordering.
// LargeVectors: filled, and their pages first touched, by the registering threads.
struct SortedCoordinates {
  LargeVector<double> x, y, z, diameter;
  std::size_t size() const { return x.size(); }
};

// Whether registration indexes only the occupied cells (hashed) rather than every key (dense),
// for the grid index a variant asks for. kAuto: hashed when the grid does not fit a dense table
// (more than CellGrid::kMaxKeys keys), or when the table would hold more than
// kDenseKeysPerParticle keys per particle and more than kDenseKeysAlways keys (filling it and
// the cell loop's empty iterations would then cost more than the particles; the paper's scene,
// N = 1,024,000 at D = 1/200, has 7.7 keys per particle and stays dense). Throws InputError for
// kDense on a grid that does not fit.
inline constexpr std::uint64_t kDenseKeysPerParticle = 64;
inline constexpr std::uint64_t kDenseKeysAlways = std::uint64_t{1} << 24;
bool use_hashed_index(GridIndex index, const CellGrid& grid, std::size_t particles);

// The occupied cells of a registration in ascending key order, with where each one's
// particles start, and an open-addressing hash table from key to place in the list (linear
// probing; capacity a power of two at least twice the cells, so probes stay short). Most keys a
// stencil asks for are empty cells on a sparse grid, and a table larger than the caches answers
// each with a miss to memory; a one-bit-per-slot filter of 8 to 16 bits per cell (1 MB for
// 10^6 cells: it stays in L2) answers most of them first. Memory about 12 bytes per occupied
// cell plus 32 to 64 in the table and 1 to 2 in the filter: O(N) whatever the grid.
struct OccupiedCells {
  struct Entry {
    std::uint64_t key;
    std::uint32_t cell;
  };
  static constexpr std::uint64_t kEmpty = UINT64_MAX;  // above every key (keys < 2^63)
  static constexpr std::uint32_t kNone = UINT32_MAX;

  LargeVector<std::uint64_t> key;    // ascending
  LargeVector<std::uint32_t> begin;  // size() + 1 entries: cell c holds [begin[c], begin[c + 1])
  LargeVector<Entry> table;
  LargeVector<std::uint64_t> filter;  // bit (h >> filter_shift) set for every key's hash h
  int shift = 63;                     // a key's home in the table: h >> shift
  int filter_shift = 63;

  std::uint64_t size() const { return key.size(); }
  // The place of the cell with key k in the list, or kNone when it holds no particle.
  std::uint32_t find(std::uint64_t k) const {
    const std::uint64_t h = k * kFibonacci;
    const std::uint64_t bit = h >> filter_shift;
    if (((filter[bit >> 6] >> (bit & 63)) & 1) == 0) return kNone;
    const std::uint64_t mask = table.size() - 1;
    for (std::uint64_t at = h >> shift;; at = (at + 1) & mask) {
      const Entry& e = table[at];
      if (e.key == k) return e.cell;
      if (e.key == kEmpty) return kNone;
    }
  }
  // Bytes held by the list, the table and the filter.
  std::size_t bytes() const;
  // Fills the table and the filter from `key` (on `threads` threads).
  void build_table(int threads);

 private:
  // 2^64 / golden ratio: consecutive keys (a row of cells) land far apart in the table.
  static constexpr std::uint64_t kFibonacci = 0x9e3779b97f4a7c15ull;
};

// Particles registered in cells (sorted by cell key, stably): slot s holds input particle
// slot_particle[s], and a cell's particles occupy consecutive slots. With the dense index the
// cell with key k holds slots [cell_begin[k], cell_begin[k + 1]); with the hashed one `occupied`
// lists the occupied cells (their wide keys) and where each one's slots begin.
struct CellRegistry {
  bool hashed = false;
  LargeVector<std::uint32_t> cell_begin;     // dense: key_count + 1 entries; hashed: empty
  OccupiedCells occupied;                    // hashed only
  LargeVector<std::uint32_t> slot_particle;  // slot -> input index
  LargeVector<std::uint32_t> particle_slot;  // input index -> slot
  std::uint32_t max_occupancy = 0;
  // Sum over cells of occupancy^2: divided by the particle count, the mean occupancy of a
  // particle's own cell (itself included), what a particle's stencil holds per cell.
  std::uint64_t occupancy_squares = 0;
  // The last assign's parts, seconds: the keys, the sort and the cell index; the reordering (or
  // the unsorted layout's inverse map). Where T_s goes as threads are added (issue #47).
  double registration_s = 0.0, reorder_s = 0.0;

  // Registers the particles. With `sorted`, also copies the coordinates (and diameters) into
  // slot order: the paper's reordering. particle_slot is filled only without it (the
  // unsorted layout needs it; sorted ones use slots as ids). Runs on `threads` threads (keys,
  // the radix sort's passes, the cell index, the reordering); the result is the same for any
  // thread count. `hashed_index` chooses the index (see use_hashed_index); a dense index on a
  // grid that does not fit one throws InputError.
  void assign(const CellGrid& grid, const Scene& scene, SortedCoordinates* sorted = nullptr,
              int threads = 1, bool hashed_index = false);

  // Frees what only assign() reads (the sort's entries, the staged records), keeping the
  // index and the slots; the next assign() reallocates it.
  void release_scratch();

  // Bytes held by the cell index (the dense table, or the occupied cells and their table).
  std::size_t index_bytes() const;
  // Bytes of everything registered: the index, the slots and the sort's buffers (their
  // entries); the same at any thread count but for the sort's per-thread digit counts.
  std::size_t buffer_bytes() const;

 private:
  // Radix sort entries: a cell key and an input index. Keys below 2^32 share one word with the
  // index; wider keys (hashed grids of more than 2^32 keys) take two.
  struct NarrowEntry {
    std::uint64_t bits;
    static NarrowEntry make(std::uint64_t key, std::size_t i) { return {key << 32 | i}; }
    std::uint64_t key() const { return bits >> 32; }
    std::uint32_t index() const { return static_cast<std::uint32_t>(bits); }
  };
  struct WideEntry {
    std::uint64_t key_;
    std::uint32_t index_;
    static WideEntry make(std::uint64_t key, std::size_t i) {
      return {key, static_cast<std::uint32_t>(i)};
    }
    std::uint64_t key() const { return key_; }
    std::uint32_t index() const { return index_; }
  };
  // A particle's coordinates and diameter (0 without per-particle diameters) side by side, in
  // input order: the reordering's gather reads one 32-byte record, half a line, where reading
  // the scene's arrays took a line of each (and, in std::vector's 4 KiB pages, a TLB miss of
  // each) at random.
  struct alignas(32) StagedParticle {
    double x, y, z, diameter;
  };
  // With `staged`, the keys' pass also writes every particle's record there (the coordinates are
  // in L1 from the keys).
  template <class Entry>
  void sort_and_index(const CellGrid& grid, const Scene& scene, std::size_t team, int key_bits,
                      LargeVector<Entry>& buffer, LargeVector<Entry>& scratch,
                      StagedParticle* staged);

  LargeVector<StagedParticle> staged_;  // sorted orders only: the reordering's source
  LargeVector<NarrowEntry> sort_buffer_, sort_scratch_;
  LargeVector<WideEntry> wide_buffer_, wide_scratch_;
  std::vector<std::uint64_t> histograms_;    // per thread, the radix digit counts
  std::vector<std::uint64_t> new_cells_;     // per thread, occupied cells starting in its slots
  std::vector<std::uint64_t> bucket_begin_;  // the first pass's buckets' first entries
  std::vector<std::uint64_t> range_totals_;  // per thread, the entries of its range of buckets
};

}  // namespace contactlab
