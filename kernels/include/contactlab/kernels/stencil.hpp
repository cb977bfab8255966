// The cell stencil as rows of consecutive cells, and the slot ranges it covers around a home
// cell: what the traversal (traverse.hpp) reads per home, and what it builds once per cell to
// weigh the balanced schedule's homes by their pair tests.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>

#include "contactlab/kernels/cell_grid.hpp"
#include "contactlab/kernels/slot_range.hpp"
#include "contactlab/kernels/variant.hpp"

namespace contactlab::traversal {

// The stencil as rows of cells along x: for each (dy, dz) the cells dx in [dx_lo, dx_hi].
// With the linear numbering a row's cells are consecutive keys, so its particles are one slot
// range found with two loads. Rows are in ascending key order (z, then y).
struct StencilRow {
  int dy, dz, dx_lo, dx_hi;
  // Linear numbering: the row's first and last keys less the home cell's (see with_key_steps).
  std::int64_t first_key = 0, last_key = 0;
};

struct StencilRows {
  std::array<StencilRow, 9> rows{};
  int count = 0;
  int own = 0;  // the row holding the home cell

  // The rows' keys relative to the home cell's in a linear numbering of `dims` cells: a home
  // away from the grid's faces finds its rows by addition alone.
  StencilRows& with_key_steps(const std::array<int, 3>& dims) {
    const std::int64_t y_step = dims[0], z_step = std::int64_t{dims[0]} * dims[1];
    for (StencilRow& row : rows) {
      const std::int64_t start = row.dz * z_step + row.dy * y_step;
      row.first_key = start + row.dx_lo;
      row.last_key = start + row.dx_hi;
    }
    return *this;
  }
};

inline StencilRows make_stencil(Stencil stencil) {
  StencilRows result;
  for (int dz = -1; dz <= 1; ++dz) {
    for (int dy = -1; dy <= 1; ++dy) {
      // Forward half: own cell and the cells (dz, dy, dx) lexicographically after (0, 0, 0),
      // so each unordered pair of distinct neighbour cells is visited from one of them only.
      const bool before_own = dz < 0 || (dz == 0 && dy < 0);
      if (stencil == Stencil::kHalf && before_own) continue;
      const bool own = dz == 0 && dy == 0;
      if (own) result.own = result.count;
      const int dx_lo = stencil == Stencil::kHalf && own ? 0 : -1;
      result.rows[result.count++] = {dy, dz, dx_lo, 1};
    }
  }
  return result;
}

// The particles of a home cell's stencil as slot ranges, ranges[own] holding the home cell.
// With the half stencil ranges[own] starts at the home cell (no stencil cell precedes it).
struct NeighbourRanges {
  std::array<SlotRange, 27> ranges{};
  int count = 0;
  int own = 0;
  std::uint64_t candidates = 0;  // slots in all ranges, the home particle's own included

  // Pair tests of the home particle in slot s_h: with the half stencil only the own range's
  // later slots, with the full one every slot but its own.
  std::uint64_t tests_from(std::uint32_t s_h, bool half) const {
    return candidates - (half ? s_h + 1 - ranges[own].begin : 1);
  }

  // The ranges of the stencil around the home cell, found through the registration's cell
  // index (cell_index.hpp: DenseCellIndex or HashedCellIndex).
  // `span` cells along x from `home` (a tile: linear numbering only) share the ranges: each row
  // reaches from the first one's x - 1 to the last one's x + 1.
  template <class Index>
  void build(const CellGrid& grid, const Index& index, const StencilRows& stencil,
             const std::array<int, 3>& home, int span = 1) {
    count = 0;
    candidates = 0;
    const auto& dims = grid.dims();
    const bool linear = grid.numbering() == CellNumbering::kLinear;
    const int widen = span - 1;
    if (linear && home[0] > 0 && home[1] > 0 && home[2] > 0 && home[0] + span < dims[0] &&
        home[1] + 1 < dims[1] && home[2] + 1 < dims[2]) {
      // Away from the faces every row is in the grid: its keys by addition, no bounds (the
      // multiplications and clamps of the general case below were half of a sparse home's
      // range build).
      // The count, the own range and the candidates in locals, stored once: as members each
      // row's store to ranges[] made them a store and a reload per row (GCC cannot tell the
      // array from them), a chain through memory across the nine rows.
      const auto centre = static_cast<std::int64_t>(index.key(grid, home[0], home[1], home[2]));
      int kept = 0, own_at = 0;
      std::uint64_t total = 0;
      const int rows = stencil.count, own_row = stencil.own;
      for (int r = 0; r < rows; ++r) {
        const StencilRow& row = stencil.rows[r];
        const SlotRange range =
            index.key_range(r, static_cast<std::uint64_t>(centre + row.first_key),
                            static_cast<std::uint64_t>(centre + row.last_key + widen));
        index.prefetch_ahead(static_cast<std::uint64_t>(centre + row.first_key));
        own_at = r == own_row ? kept : own_at;
        ranges[kept] = range;  // kept only if it holds a particle, as below
        kept += range.begin != range.end;
        total += range.end - range.begin;
      }
      count = kept;
      own = own_at;
      candidates = total;
      return;
    }
    std::array<std::uint64_t, 3> x_part{};  // Morton: the x parts of the home's x - 1 .. x + 1
    if (!linear) {
      for (int i = 0; i < 3; ++i) x_part[i] = Index::morton_part(0, home[0] - 1 + i);
    }
    for (int r = 0; r < stencil.count; ++r) {
      const StencilRow& row = stencil.rows[r];
      const int cy = home[1] + row.dy, cz = home[2] + row.dz;
      if (cy < 0 || cz < 0 || cy >= dims[1] || cz >= dims[2]) continue;
      const int x_lo = std::max(home[0] + row.dx_lo, 0);
      const int x_hi = std::min(home[0] + row.dx_hi + widen, dims[0] - 1);
      if (linear) {
        if (r == stencil.own) own = count;
        const SlotRange range =
            index.key_range(r, index.key(grid, x_lo, cy, cz), index.key(grid, x_hi, cy, cz));
        // Kept only if it holds a particle (never empty: the own row, which holds the home),
        // without a branch: around the sparse cells that make most of a clustered scene's
        // homes, whether a row is empty is a coin toss.
        ranges[count] = range;
        count += range.begin != range.end;
        candidates += range.end - range.begin;
        continue;
      }
      // Morton keys of a row are not consecutive: one range per cell.
      const std::uint64_t yz_part = Index::morton_part(1, cy) | Index::morton_part(2, cz);
      for (int cx = x_lo; cx <= x_hi; ++cx) {
        const std::uint64_t key = x_part[cx - home[0] + 1] | yz_part;
        const SlotRange range = index.key_range(3 * r + cx - home[0] + 1, key, key);
        if (r == stencil.own && cx == home[0]) own = count;  // the home cell is never empty
        ranges[count] = range;
        count += range.begin != range.end;  // as above, without a branch
        candidates += range.end - range.begin;
      }
    }
  }
};

}  // namespace contactlab::traversal
