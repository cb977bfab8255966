// How the traversal finds the particles of a cell once they are registered (sorted by cell key):
// a dense table with one entry per key (the paper's; memory and cell-loop iterations grow with
// the grid), or the occupied cells only, found through a hash table (memory and iterations grow
// with N: grids with far more cells than particles, e.g. D = 1e-4 in a unit box, 10^12 cells).
// Both read the same slot order, so both give the same candidates in the same order. The
// traversal (traverse.hpp) is written once over either index type.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>

#include "contactlab/kernels/cell_grid.hpp"
#include "contactlab/kernels/slot_range.hpp"

namespace contactlab {

// The dense table: the particles of the cell with key k are slots [begin[k], begin[k + 1]).
struct DenseCellIndex {
  const std::uint32_t* begin;
  std::uint64_t keys;

  // The cell loop runs over every key, empty cells included (paper Fig. 4).
  std::uint64_t cell_iterations() const { return keys; }
  SlotRange iteration_slots(std::uint64_t k) const { return {begin[k], begin[k + 1]}; }
  std::uint64_t key(const CellGrid& grid, int cx, int cy, int cz) const {
    return grid.key(cx, cy, cz);
  }
  static std::uint64_t morton_part(int axis, int c) { return CellGrid::morton_part(axis, c); }
  // The particles of the cells with keys first..last (consecutive keys: in the linear numbering
  // the cells of a row along x), one slot range since slots are sorted by key. `at` (the
  // stencil position asking) only matters to the hashed index.
  SlotRange key_range(int /*at*/, std::uint64_t first, std::uint64_t last) const {
    return {begin[first], begin[last + 1]};
  }
  // The slots of the cell with key k (a home's own cell), and of the cells first..last.
  SlotRange cell_slots(std::uint64_t k) const { return {begin[k], begin[k + 1]}; }
  SlotRange cell_slots_of(std::uint64_t first, std::uint64_t last) const {
    return {begin[first], begin[last + 1]};
  }
  // Asks for the entries two lines past key k: a row of the next homes' stencils along x. The
  // nine rows' loads of a range build missed the caches (the table is 4 bytes a cell, 32 MB at
  // 199^3 cells), and the hardware prefetcher does not follow nine streams that skip ahead.
  void prefetch_ahead(std::uint64_t k) const { __builtin_prefetch(begin + k + 32); }
};

// The occupied cells (OccupiedCells), found two ways, chosen by how the loop visits homes:
// - in key order (the cell loop, and the particle loop over sorted particles): each stencil
//   cell's key grows with the home's, so each of the 27 stencil positions keeps a cursor into
//   the ascending key list and gallops from it (exponential then binary search): near the last
//   answer, in cached memory. At D = 1e-4, N = 1,024,000 this was 3x faster than a binary
//   search per row and 5x faster than the filtered hash table, which sends probes to memory;
// - in input order (the particle loop over unsorted particles): the hash table, whose filter
//   answers most empty cells from L2 (there about 1.3x faster than the binary search).
// An index value is per thread (each thread calls traverse() with its own), so the cursors are
// not shared.
struct HashedCellIndex {
  const OccupiedCells* cells;
  bool homes_in_key_order;
  // Per stencil position (at most 27 with Morton keys) its last answer, then the home cell's.
  static constexpr int kHomeCursor = 27;
  mutable std::array<std::uint64_t, kHomeCursor + 1> cursor{};

  // The cell loop runs over the occupied cells only, in key order.
  std::uint64_t cell_iterations() const { return cells->size(); }
  SlotRange iteration_slots(std::uint64_t c) const {
    return {cells->begin[c], cells->begin[c + 1]};
  }
  std::uint64_t key(const CellGrid& grid, int cx, int cy, int cz) const {
    return grid.wide_key(cx, cy, cz);
  }
  static std::uint64_t morton_part(int axis, int c) { return CellGrid::wide_morton_part(axis, c); }
  // first..last are consecutive keys (a stencil row, or a tile's cells), asked for by stencil
  // position `at`. The occupied cells among them are consecutive in the list.
  SlotRange key_range(int at, std::uint64_t first, std::uint64_t last) const {
    const std::uint64_t* keys = cells->key.data();
    const std::uint64_t m = cells->size();
    std::uint64_t c = m;
    if (homes_in_key_order) {
      c = cursor[at] = seek(cursor[at], first);
    } else {
      // Probe in order until one is occupied (the list is read in sequence after it).
      for (std::uint64_t k = first; k <= last && c == m; ++k) {
        const std::uint32_t found = cells->find(k);
        if (found != OccupiedCells::kNone) c = found;
      }
    }
    std::uint64_t end = c;
    while (end < m && keys[end] <= last) ++end;
    return {cells->begin[c], cells->begin[end]};
  }
  SlotRange cell_slots(std::uint64_t k) const { return key_range(kHomeCursor, k, k); }
  SlotRange cell_slots_of(std::uint64_t first, std::uint64_t last) const {
    return key_range(kHomeCursor, first, last);
  }
  void prefetch_ahead(std::uint64_t) const {}  // its cursors read ahead by themselves

 private:
  // The first place in the key list whose key is >= target, galloping from `hint`.
  std::uint64_t seek(std::uint64_t hint, std::uint64_t target) const {
    const std::uint64_t* keys = cells->key.data();
    const std::uint64_t m = cells->size();
    const std::uint64_t h = std::min(hint, m);
    std::uint64_t lo = 0, hi = 0;
    if (h < m && keys[h] < target) {  // the answer lies after h
      std::uint64_t below = h, bound = 1;
      while (h + bound < m && keys[h + bound] < target) {
        below = h + bound;
        bound *= 2;
      }
      lo = below + 1;
      hi = std::min(h + bound, m);
    } else {  // at h or before it
      std::uint64_t above = h, bound = 1;
      while (bound <= h && keys[h - bound] >= target) {
        above = h - bound;
        bound *= 2;
      }
      lo = bound <= h ? h - bound + 1 : 0;
      hi = above;
    }
    return static_cast<std::uint64_t>(std::lower_bound(keys + lo, keys + hi, target) - keys);
  }
};

}  // namespace contactlab
