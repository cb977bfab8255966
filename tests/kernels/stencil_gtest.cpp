// The stencil's rows and a home cell's slot ranges (stencil.hpp), against the definition counted
// cell by cell: the full stencil's 27 cells and the half stencil's own cell and 13 forward ones,
// clipped at the grid's faces, on a grid whose cells hold 0, 1 or 2 particles by key.
#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "contactlab/kernels/cell_index.hpp"
#include "contactlab/kernels/stencil.hpp"

namespace contactlab::traversal {
namespace {

TEST(StencilRows, FullHasNineRowsOfThreeHalfHasFiveStartingAtTheHome) {
  const StencilRows full = make_stencil(Stencil::kFull);
  ASSERT_EQ(full.count, 9);
  for (int r = 0; r < full.count; ++r) {
    EXPECT_EQ(full.rows[r].dx_lo, -1);
    EXPECT_EQ(full.rows[r].dx_hi, 1);
  }
  EXPECT_EQ(full.rows[full.own].dy, 0);
  EXPECT_EQ(full.rows[full.own].dz, 0);
  const StencilRows half = make_stencil(Stencil::kHalf);
  ASSERT_EQ(half.count, 5);
  EXPECT_EQ(half.own, 0);  // no row of the half stencil precedes the home's
  EXPECT_EQ(half.rows[0].dx_lo, 0);
  int cells = 0;
  for (int r = 0; r < half.count; ++r) cells += half.rows[r].dx_hi - half.rows[r].dx_lo + 1;
  EXPECT_EQ(cells, 14);  // the own cell and 13 forward
}

TEST(StencilRows, KeyStepsAreTheLinearKeysOfTheRowsEnds) {
  const std::array<int, 3> dims{5, 4, 3};
  const StencilRows full = make_stencil(Stencil::kFull).with_key_steps(dims);
  for (int r = 0; r < full.count; ++r) {
    const StencilRow& row = full.rows[r];
    EXPECT_EQ(row.first_key, row.dz * 20 + row.dy * 5 - 1);
    EXPECT_EQ(row.last_key, row.dz * 20 + row.dy * 5 + 1);
  }
}

// A 5 x 4 x 3 grid (linear keys), cell k holding k % 3 particles in key order.
struct SmallGrid {
  CellGrid grid{Box{{0, 0, 0}, {1, 0.8, 0.6}}, 0.19, CellNumbering::kLinear};
  std::vector<std::uint32_t> begin;
  SmallGrid() {
    begin.push_back(0);
    for (std::uint64_t k = 0; k < grid.key_count(); ++k)
      begin.push_back(begin.back() + static_cast<std::uint32_t>(k % 3));
  }
  DenseCellIndex index() const { return {begin.data(), grid.key_count()}; }
  std::uint64_t occupancy(int x, int y, int z) const { return grid.key(x, y, z) % 3; }
};

TEST(NeighbourRanges, CoverTheStencilsCellsEverywhereFacesIncluded) {
  const SmallGrid g;
  const auto& dims = g.grid.dims();
  ASSERT_EQ(dims, (std::array<int, 3>{5, 4, 3}));
  for (const Stencil stencil : {Stencil::kFull, Stencil::kHalf}) {
    const StencilRows rows = make_stencil(stencil).with_key_steps(dims);
    for (int z = 0; z < dims[2]; ++z) {
      for (int y = 0; y < dims[1]; ++y) {
        for (int x = 0; x < dims[0]; ++x) {
          if (g.occupancy(x, y, z) == 0) continue;  // a home's cell holds it
          NeighbourRanges nb;
          nb.build(g.grid, g.index(), rows, {x, y, z});
          std::uint64_t expected = 0;
          for (int dz = -1; dz <= 1; ++dz) {
            for (int dy = -1; dy <= 1; ++dy) {
              for (int dx = -1; dx <= 1; ++dx) {
                const bool before = dz < 0 || (dz == 0 && (dy < 0 || (dy == 0 && dx < 0)));
                if (stencil == Stencil::kHalf && before) continue;
                if (g.grid.in_range(x + dx, y + dy, z + dz))
                  expected += g.occupancy(x + dx, y + dy, z + dz);
              }
            }
          }
          EXPECT_EQ(nb.candidates, expected) << x << " " << y << " " << z;
          std::uint64_t in_ranges = 0;
          for (int r = 0; r < nb.count; ++r) {
            EXPECT_LT(nb.ranges[r].begin, nb.ranges[r].end);  // only rows with a particle
            in_ranges += nb.ranges[r].end - nb.ranges[r].begin;
          }
          EXPECT_EQ(in_ranges, expected);
          const SlotRange own = g.index().cell_slots(g.grid.key(x, y, z));
          EXPECT_LE(nb.ranges[nb.own].begin, own.begin);
          EXPECT_GE(nb.ranges[nb.own].end, own.end);
          // A home's tests: every candidate but itself (full), or the own row's later slots and
          // the forward rows (half).
          const bool half = stencil == Stencil::kHalf;
          for (std::uint32_t s = own.begin; s < own.end; ++s) {
            EXPECT_EQ(nb.tests_from(s, half), half ? expected - (s + 1 - own.begin) : expected - 1);
          }
        }
      }
    }
  }
}

}  // namespace
}  // namespace contactlab::traversal
