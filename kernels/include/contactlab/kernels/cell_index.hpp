// How the traversal finds the particles of a cell once they are registered (sorted by cell key):
// a dense table with one entry per key (the paper's; memory and cell-loop iterations grow with
// the grid), or the occupied cells only, found through a hash table (memory and iterations grow
// with N: grids with far more cells than particles, e.g. D = 1e-4 in a unit box, 10^12 cells).
// Both read the same slot order, so both give the same candidates in the same order. The
// traversal (traverse.hpp) is written once over either index type.
#pragma once

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
  // the cells of a row along x), one slot range since slots are sorted by key.
  SlotRange key_range(std::uint64_t first, std::uint64_t last) const {
    return {begin[first], begin[last + 1]};
  }
};

// The occupied cells: an open-addressing hash table (linear probing, load at most 1/2) from a
// cell's 64-bit key to its place in the ascending list of occupied keys, whose neighbours in
// the list are the next occupied cells in key order.
struct HashedCellIndex {
  const OccupiedCells* cells;

  // The cell loop runs over the occupied cells only, in key order.
  std::uint64_t cell_iterations() const { return cells->size(); }
  SlotRange iteration_slots(std::uint64_t c) const {
    return {cells->begin[c], cells->begin[c + 1]};
  }
  std::uint64_t key(const CellGrid& grid, int cx, int cy, int cz) const {
    return grid.wide_key(cx, cy, cz);
  }
  static std::uint64_t morton_part(int axis, int c) { return CellGrid::wide_morton_part(axis, c); }
  // first..last are at most 3 consecutive keys: probe them in order until one is occupied; the
  // occupied ones after it follow it in the list (probing is what costs, the list is read in
  // sequence).
  SlotRange key_range(std::uint64_t first, std::uint64_t last) const {
    for (std::uint64_t k = first; k <= last; ++k) {
      const std::uint32_t c = cells->find(k);
      if (c == OccupiedCells::kNone) continue;
      std::uint64_t end = c + std::uint64_t{1};
      while (end < cells->size() && cells->key[end] <= last) ++end;
      return {cells->begin[c], cells->begin[end]};
    }
    return {0, 0};
  }
};

}  // namespace contactlab
