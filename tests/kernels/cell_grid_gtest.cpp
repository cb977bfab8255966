// CellGrid (dims, widening, coordinates, keys) and CellRegistry (the counting sort).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <limits>
#include <set>
#include <vector>

#include "contactlab/kernels/error.hpp"
#include "test_support.hpp"

namespace contactlab::test {
namespace {

using Dims = std::array<int, 3>;

// The header's formula: G = max(1, floor(L / w)), w = D (1 + 2^-40).
int expected_dim(double extent, double d) {
  const double w = d * (1.0 + 0x1.0p-40);
  return std::max(1, static_cast<int>(std::floor(extent / w)));
}

TEST(CellGrid, DimsFollowTheDocumentedFormula) {
  // D = 1/200 in the unit box: 1 / (D (1 + 2^-40)) is just below 200, so 199 cells.
  EXPECT_EQ(CellGrid(Box{}, 1.0 / 200.0, CellNumbering::kLinear).dims(), (Dims{199, 199, 199}));
  EXPECT_EQ(CellGrid(Box{}, 0.1, CellNumbering::kLinear).dims(), (Dims{9, 9, 9}));
  EXPECT_EQ(CellGrid(Box{}, 0.25, CellNumbering::kLinear).dims(), (Dims{3, 3, 3}));
  EXPECT_EQ(CellGrid(Box{}, 0.3, CellNumbering::kLinear).dims(), (Dims{3, 3, 3}));
  EXPECT_EQ(CellGrid(Box{}, 1.0 / 256.0, CellNumbering::kLinear).dims(), (Dims{255, 255, 255}));
  // Slightly below 1/200, the widening no longer drops a cell.
  EXPECT_EQ(CellGrid(Box{}, 1.0 / 200.0 * (1.0 - 1e-9), CellNumbering::kLinear).dims(),
            (Dims{200, 200, 200}));
  // D >= the box: one cell.
  EXPECT_EQ(CellGrid(Box{}, 1.0, CellNumbering::kLinear).dims(), (Dims{1, 1, 1}));
  EXPECT_EQ(CellGrid(Box{}, 0.9, CellNumbering::kLinear).dims(), (Dims{1, 1, 1}));
  EXPECT_EQ(CellGrid(Box{}, 1e6, CellNumbering::kLinear).dims(), (Dims{1, 1, 1}));
  // Anisotropic, offset box.
  const Box box{{-1.0, 2.0, 10.0}, {1.0, 2.5, 13.0}};
  // 3 / 0.3 is 10 in exact arithmetic, but the widened width makes it 9.99999999999...
  EXPECT_EQ(CellGrid(box, 0.3, CellNumbering::kLinear).dims(), (Dims{6, 1, 9}));
  for (const double d : {0.001 * 7, 0.013, 0.02, 0.0625, 1.0 / 3.0, 0.49, 0.5, 0.51}) {
    for (const Box& b : {Box{}, box}) {
      const CellGrid grid(b, d, CellNumbering::kLinear);
      for (int axis = 0; axis < 3; ++axis) {
        EXPECT_EQ(grid.dims()[axis], expected_dim(b.extent(axis), d))
            << "D = " << d << " axis " << axis;
        // Cells are at least D wide (unless one cell spans a box narrower than D), so
        // neighbours within D are at most one cell apart.
        if (grid.dims()[axis] > 1) {
          EXPECT_GE(grid.cell_width()[axis], d) << "D = " << d;
        }
        EXPECT_DOUBLE_EQ(grid.cell_width()[axis] * grid.dims()[axis], b.extent(axis));
      }
      EXPECT_EQ(grid.cell_count(), std::uint64_t(grid.dims()[0]) * grid.dims()[1] * grid.dims()[2]);
    }
  }
}

TEST(CellGrid, RejectsBadWidths) {
  for (const double d :
       {0.0, -0.0, -1.0, std::numeric_limits<double>::quiet_NaN(),
        std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()}) {
    EXPECT_THROW(CellGrid(Box{}, d, CellNumbering::kLinear), InputError) << "D = " << d;
    EXPECT_THROW(CellGrid(Box{}, d, CellNumbering::kMorton), InputError) << "D = " << d;
  }
  // More than 2^28 keys is a grid for the hashed index, not an error (hashed_grid_gtest.cpp).
  EXPECT_FALSE(CellGrid(Box{}, 1e-4, CellNumbering::kLinear).dense_fits());
  EXPECT_FALSE(CellGrid(Box{}, 1e-4, CellNumbering::kMorton).dense_fits());
  EXPECT_TRUE(CellGrid(Box{}, 1.0 / 512, CellNumbering::kMorton).dense_fits());
  // The limits are per axis: 2^30 cells (linear), 2^21 (Morton, 21 key bits an axis).
  EXPECT_THROW(CellGrid(Box{}, 1e-300, CellNumbering::kLinear), InputError);
  // The message names D as given (std::to_string's six decimals printed "0.000000").
  try {
    CellGrid(Box{}, 1e-300, CellNumbering::kLinear);
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("D = 1e-300 "), std::string::npos) << e.what();
  }
  EXPECT_THROW(CellGrid(Box{}, 1e-7, CellNumbering::kMorton), InputError);
  EXPECT_NO_THROW(CellGrid(Box{}, 1e-6, CellNumbering::kMorton));
  const Box thin{{0, 0, 0}, {double(CellGrid::kMaxKeys * 2), 1, 1}};
  EXPECT_NO_THROW(CellGrid(thin, 1.0, CellNumbering::kLinear));
  const Box thinner{{0, 0, 0}, {double(CellGrid::kMaxAxisCells) * 2, 1, 1}};
  EXPECT_THROW(CellGrid(thinner, 1.0, CellNumbering::kLinear), InputError);
  // Linear keys must fit in 62 bits: 2^21 x 2^21 x 2^21 cells do not.
  const Box cube{{0, 0, 0}, {0x1.0p21 + 1, 0x1.0p21 + 1, 0x1.0p21 + 1}};
  EXPECT_THROW(CellGrid(cube, 1.0, CellNumbering::kLinear), InputError);
}

TEST(NumberText, IsTheShortestTextThatReadsBack) {
  EXPECT_EQ(number_text(0.005), "0.005");
  EXPECT_EQ(number_text(1e-300), "1e-300");
  EXPECT_EQ(number_text(-1.0), "-1");
  EXPECT_EQ(number_text(std::numeric_limits<double>::infinity()), "inf");
  for (const double v : {0.1 + 0.2, 1.0 / 3.0, 6.02214076e23, 5e-324}) {
    EXPECT_EQ(std::strtod(number_text(v).c_str(), nullptr), v) << number_text(v);
  }
}

TEST(CellGrid, WideKeysAreTheKeysWhereBothExist) {
  for (const auto numbering : {CellNumbering::kLinear, CellNumbering::kMorton}) {
    const CellGrid grid(Box{{0, 0, 0}, {1, 2, 3}}, 0.11, numbering);
    const auto& dims = grid.dims();
    for (int cz = 0; cz < dims[2]; ++cz) {
      for (int cy = 0; cy < dims[1]; ++cy) {
        for (int cx = 0; cx < dims[0]; ++cx) {
          ASSERT_EQ(grid.wide_key(cx, cy, cz), grid.key(cx, cy, cz));
        }
      }
    }
  }
  // Beyond 32 bits: linear keys are (z G_y + y) G_x + x, Morton keys interleave 21 bits.
  const CellGrid linear(Box{}, 1e-5, CellNumbering::kLinear);
  const std::uint64_t g = static_cast<std::uint64_t>(linear.dims()[0]);
  EXPECT_EQ(linear.wide_key(1, 2, 3), (3 * g + 2) * g + 1);
  EXPECT_EQ(linear.wide_key(linear.dims()[0] - 1, linear.dims()[1] - 1, linear.dims()[2] - 1),
            linear.cell_count() - 1);
  const CellGrid morton(Box{}, 1e-6, CellNumbering::kMorton);
  EXPECT_EQ(morton.wide_key(1 << 20, 0, 0), std::uint64_t{1} << 60);
  EXPECT_EQ(morton.wide_key(0, 1 << 20, 1 << 20), std::uint64_t{3} << 61);
}

TEST(CellGrid, UpperFacesLandInTheLastCell) {
  for (const double d : {1.0 / 200.0, 0.1, 0.3, 1.0 / 7.0, 2.0}) {
    for (const auto numbering : {CellNumbering::kLinear, CellNumbering::kMorton}) {
      // (599 cells on x at D = 1/200 would need 2^30 Morton keys: linear numbering only.)
      if (numbering == CellNumbering::kMorton && d < 0.01) continue;
      const Box box{{-1.0, 0.0, 5.0}, {2.0, 1.0, 5.5}};
      const CellGrid grid(box, d, numbering);
      const Dims last{grid.dims()[0] - 1, grid.dims()[1] - 1, grid.dims()[2] - 1};
      EXPECT_EQ(grid.coords_of(2.0, 1.0, 5.5), last) << "D = " << d;
      EXPECT_EQ(grid.coords_of(-1.0, 0.0, 5.0), (Dims{0, 0, 0}));
      EXPECT_EQ(grid.coords_of(2.0, 0.0, 5.0)[0], last[0]);
      EXPECT_EQ(grid.coords_of(-1.0, 1.0, 5.0)[1], last[1]);
      EXPECT_EQ(grid.coords_of(-1.0, 0.0, 5.5)[2], last[2]);
      // Just inside the upper face: still the last cell.
      EXPECT_EQ(grid.coords_of(std::nextafter(2.0, 0.0), std::nextafter(1.0, 0.0),
                               std::nextafter(5.5, 0.0)),
                last);
    }
  }
}

TEST(CellGrid, CoordinatesAreInRangeAndMonotone) {
  const Box box{{-1.0, 0.0, 5.0}, {2.0, 1.0, 5.5}};
  const CellGrid grid(box, 0.037, CellNumbering::kLinear);
  Xoshiro256 rng(3);
  for (int k = 0; k < 20000; ++k) {
    const double x = -1.0 + 3.0 * rng.uniform(), y = rng.uniform(), z = 5.0 + 0.5 * rng.uniform();
    const auto c = grid.coords_of(x, y, z);
    ASSERT_TRUE(grid.in_range(c[0], c[1], c[2]));
    // The cell is where the point is, up to rounding at the faces.
    const double slack = 1e-12;
    ASSERT_GE(x, box.lo[0] + c[0] * grid.cell_width()[0] - slack);
    ASSERT_LE(x, box.lo[0] + (c[0] + 1) * grid.cell_width()[0] + slack);
    ASSERT_GE(z, box.lo[2] + c[2] * grid.cell_width()[2] - slack);
    ASSERT_LE(z, box.lo[2] + (c[2] + 1) * grid.cell_width()[2] + slack);
  }
  int previous = 0;
  for (double x = -1.0; x <= 2.0; x += 1e-4) {
    const int c = grid.coords_of(x, 0.5, 5.2)[0];
    ASSERT_GE(c, previous);
    ASSERT_LE(c, previous + 1);
    previous = c;
  }
  EXPECT_FALSE(grid.in_range(-1, 0, 0));
  EXPECT_FALSE(grid.in_range(0, grid.dims()[1], 0));
  EXPECT_TRUE(grid.in_range(grid.dims()[0] - 1, grid.dims()[1] - 1, grid.dims()[2] - 1));
}

// keys_of (the registration's vectorised loop) is wide_key(coords_of(...)) point by point: on
// both numberings, a dense and a wide grid, with points on the faces and just inside them.
TEST(CellGrid, KeysOfArePointByPointKeys) {
  const Box box{{-1.0, 0.0, 5.0}, {2.0, 1.0, 5.5}};
  for (const double d : {0.037, 2e-6}) {  // 2e-6: keys past 32 bits
    for (const auto numbering : {CellNumbering::kLinear, CellNumbering::kMorton}) {
      const CellGrid grid(box, d, numbering);
      std::vector<double> x, y, z;
      Xoshiro256 rng(11);
      for (int k = 0; k < 1000; ++k) {  // not a multiple of any vector length
        x.push_back(-1.0 + 3.0 * rng.uniform());
        y.push_back(rng.uniform());
        z.push_back(5.0 + 0.5 * rng.uniform());
      }
      for (const double lo_or_hi : {0.0, 1.0}) {
        x.push_back(lo_or_hi == 0.0 ? -1.0 : 2.0);
        y.push_back(lo_or_hi);
        z.push_back(lo_or_hi == 0.0 ? 5.0 : 5.5);
        x.push_back(std::nextafter(2.0, 0.0));
        y.push_back(std::nextafter(1.0, 0.0));
        z.push_back(std::nextafter(5.5, 0.0));
      }
      std::vector<std::uint64_t> keys(x.size());
      grid.keys_of(x.data(), y.data(), z.data(), x.size(), keys.data());
      for (std::size_t i = 0; i < x.size(); ++i) {
        const auto c = grid.coords_of(x[i], y[i], z[i]);
        ASSERT_EQ(keys[i], grid.wide_key(c[0], c[1], c[2])) << "point " << i << ", D = " << d;
      }
    }
  }
}

TEST(CellGrid, LinearKeysAreTheZYXOrder) {
  const CellGrid grid(Box{{0, 0, 0}, {1, 2, 3}}, 0.24, CellNumbering::kLinear);
  const Dims dims = grid.dims();
  ASSERT_EQ(dims, (Dims{4, 8, 12}));
  EXPECT_EQ(grid.key_count(), grid.cell_count());
  std::uint32_t expected = 0;
  for (int cz = 0; cz < dims[2]; ++cz) {
    for (int cy = 0; cy < dims[1]; ++cy) {
      for (int cx = 0; cx < dims[0]; ++cx) ASSERT_EQ(grid.key(cx, cy, cz), expected++);
    }
  }
}

TEST(CellGrid, MortonKeysAreDistinctAndInterleaved) {
  for (const double d : {0.3, 0.1, 1.0 / 33.0, 1.0 / 200.0}) {
    const CellGrid grid(Box{}, d, CellNumbering::kMorton);
    const Dims dims = grid.dims();
    // key_count is the power of 8 covering the largest axis.
    int bits = 0;
    while ((1 << bits) < dims[0]) ++bits;
    EXPECT_EQ(grid.key_count(), std::uint64_t{1} << (3 * bits)) << "D = " << d;
    EXPECT_GE(grid.key_count(), grid.cell_count());
    std::set<std::uint32_t> keys;
    for (int cz = 0; cz < dims[2]; cz += (dims[2] > 40 ? 7 : 1)) {
      for (int cy = 0; cy < dims[1]; cy += (dims[1] > 40 ? 5 : 1)) {
        for (int cx = 0; cx < dims[0]; ++cx) {
          const std::uint32_t key = grid.key(cx, cy, cz);
          ASSERT_LT(key, grid.key_count());
          ASSERT_TRUE(keys.insert(key).second) << "duplicate key";
          // Bit b of cx is key bit 3b, of cy 3b + 1, of cz 3b + 2.
          for (int b = 0; b < bits; ++b) {
            ASSERT_EQ((key >> (3 * b)) & 1u, std::uint32_t((cx >> b) & 1));
            ASSERT_EQ((key >> (3 * b + 1)) & 1u, std::uint32_t((cy >> b) & 1));
            ASSERT_EQ((key >> (3 * b + 2)) & 1u, std::uint32_t((cz >> b) & 1));
          }
        }
      }
    }
  }
  EXPECT_EQ(CellGrid(Box{}, 0.3, CellNumbering::kMorton).key(1, 1, 1), 7u);
  EXPECT_EQ(CellGrid(Box{}, 0.3, CellNumbering::kMorton).key(2, 0, 0), 8u);
}

// The radix sort: every particle in exactly one slot, in the range of its own cell, the same
// for any thread count.
void check_registry(const CellGrid& grid, const Scene& scene, int threads) {
  CellRegistry registry;
  registry.assign(grid, scene, nullptr, threads);
  const std::size_t n = scene.size();
  ASSERT_EQ(registry.cell_begin.size(), grid.key_count() + 1);
  ASSERT_EQ(registry.cell_begin.front(), 0u);
  ASSERT_EQ(registry.cell_begin.back(), n);
  ASSERT_TRUE(std::is_sorted(registry.cell_begin.begin(), registry.cell_begin.end()));
  ASSERT_EQ(registry.slot_particle.size(), n);
  ASSERT_EQ(registry.particle_slot.size(), n);
  std::vector<int> seen(n, 0);
  for (std::size_t s = 0; s < n; ++s) {
    ASSERT_LT(registry.slot_particle[s], n);
    ++seen[registry.slot_particle[s]];
    ASSERT_EQ(registry.particle_slot[registry.slot_particle[s]], s);
  }
  for (std::size_t i = 0; i < n; ++i) ASSERT_EQ(seen[i], 1) << "particle " << i;
  // A stable sort: within a cell the particles keep their input order, for any thread count.
  auto key_of = [&](std::uint32_t i) {
    const auto c = grid.coords_of(scene.x[i], scene.y[i], scene.z[i]);
    return grid.key(c[0], c[1], c[2]);
  };
  for (std::size_t s = 1; s < n; ++s) {
    const std::uint32_t i = registry.slot_particle[s - 1], j = registry.slot_particle[s];
    if (key_of(i) == key_of(j)) {
      ASSERT_LT(i, j) << "slot " << s;
    }
  }
  std::vector<std::uint32_t> count(grid.key_count(), 0);
  for (std::size_t i = 0; i < n; ++i) {
    const auto c = grid.coords_of(scene.x[i], scene.y[i], scene.z[i]);
    const std::uint32_t key = grid.key(c[0], c[1], c[2]);
    ++count[key];
    const std::uint32_t slot = registry.particle_slot[i];
    ASSERT_GE(slot, registry.cell_begin[key]);
    ASSERT_LT(slot, registry.cell_begin[key + 1]);
  }
  std::uint32_t largest = 0;
  std::uint64_t squares = 0;
  for (std::uint64_t k = 0; k < grid.key_count(); ++k) {
    ASSERT_EQ(registry.cell_begin[k + 1] - registry.cell_begin[k], count[k]) << "key " << k;
    largest = std::max(largest, count[k]);
    squares += std::uint64_t{count[k]} * count[k];
    // Sorted by key stably: within a cell, input order.
    for (std::uint32_t s = registry.cell_begin[k] + 1; s < registry.cell_begin[k + 1]; ++s) {
      ASSERT_LT(registry.slot_particle[s - 1], registry.slot_particle[s]) << "key " << k;
    }
  }
  // Also where a cell runs across the threads' ranges of slots (D = 0.6: 8 cells).
  EXPECT_EQ(registry.max_occupancy, largest);
  EXPECT_EQ(registry.occupancy_squares, squares);

  // With a `sorted` output: the same registration, and the particles copied in slot order.
  CellRegistry with_copy;
  SortedCoordinates sorted;
  with_copy.assign(grid, scene, &sorted, threads);
  EXPECT_TRUE(std::equal(with_copy.cell_begin.begin(), with_copy.cell_begin.end(),
                         registry.cell_begin.begin(), registry.cell_begin.end()));
  EXPECT_TRUE(std::equal(with_copy.slot_particle.begin(), with_copy.slot_particle.end(),
                         registry.slot_particle.begin(), registry.slot_particle.end()));
  EXPECT_EQ(with_copy.max_occupancy, registry.max_occupancy);
  ASSERT_EQ(sorted.size(), n);
  ASSERT_EQ(sorted.diameter.size(), scene.diameter.size());
  for (std::size_t s = 0; s < n; ++s) {
    const std::uint32_t i = registry.slot_particle[s];
    ASSERT_EQ(sorted.x[s], scene.x[i]);
    ASSERT_EQ(sorted.y[s], scene.y[i]);
    ASSERT_EQ(sorted.z[s], scene.z[i]);
    if (scene.has_diameters()) {
      ASSERT_EQ(sorted.diameter[s], scene.diameter[i]);
    }
  }
}

TEST(CellRegistry, CountingSortInvariants) {
  for (const auto kind : all_scene_kinds()) {
    SceneSpec spec;
    spec.kind = kind;
    spec.n = 5000;
    spec.seed = 6;
    const Scene scene = generate_scene(spec);
    for (const double d : {0.02, 0.1, 0.6}) {
      for (const auto numbering : {CellNumbering::kLinear, CellNumbering::kMorton}) {
        SCOPED_TRACE(std::string(to_string(kind)) + " D = " + std::to_string(d));
        for (const int threads : {1, 2, 3}) {
          check_registry(CellGrid(scene.box, d, numbering), scene, threads);
        }
      }
    }
  }
}

// Four radix passes (a 330^3 grid's 26-bit keys): with more than one thread the top digit goes
// first and three lower passes follow, an odd number, and the top digit (bits 18 - 25) shares
// six bits with the third lower digit (16 - 23).
TEST(CellRegistry, FourPassesTopDigitFirst) {
  SceneSpec spec;
  spec.kind = SceneKind::kClustered;
  spec.n = 20000;
  spec.seed = 8;
  const Scene scene = generate_scene(spec);
  for (const int threads : {1, 2, 3}) {
    check_registry(CellGrid(scene.box, 1.0 / 330, CellNumbering::kLinear), scene, threads);
  }
}

// The reordering's staged records (scenes past copy_for_random_reads only) and the sort's
// entries are scratch: released, the registry keeps its index and slots, and the next assign
// makes them again with the same result. Either way the sorted copy is the scene in slot order.
TEST(CellRegistry, ScratchIsReleasedAndRemade) {
  for (const std::size_t n : {std::size_t{4000}, std::size_t{140000}}) {
    SceneSpec spec;
    spec.kind = SceneKind::kPolydisperse;
    spec.n = n;
    spec.diameter = 0.002;
    spec.seed = 9;
    const Scene scene = generate_scene(spec);
    const bool staged = n * 4 * sizeof(double) >= kCopyForRandomReadsFrom;  // four arrays
    ASSERT_EQ(copy_for_random_reads(scene), staged) << n;
    const CellGrid grid(scene.box, scene.max_diameter(), CellNumbering::kLinear);
    CellRegistry registry;
    SortedCoordinates sorted;
    registry.assign(grid, scene, &sorted, 3);
    for (std::size_t s = 0; s < n; ++s) {
      const std::uint32_t i = registry.slot_particle[s];
      ASSERT_EQ(sorted.x[s], scene.x[i]);
      ASSERT_EQ(sorted.y[s], scene.y[i]);
      ASSERT_EQ(sorted.z[s], scene.z[i]);
      ASSERT_EQ(sorted.diameter[s], scene.diameter[i]);
    }
    const std::vector<std::uint32_t> slots(registry.slot_particle.begin(),
                                           registry.slot_particle.end());
    const std::size_t with_scratch = registry.buffer_bytes();
    registry.release_scratch();
    // Two 8-byte sort entries a particle, and 32 bytes staged.
    EXPECT_EQ(with_scratch - registry.buffer_bytes(), (staged ? 48 : 16) * n);
    EXPECT_TRUE(std::equal(slots.begin(), slots.end(), registry.slot_particle.begin(),
                           registry.slot_particle.end()));
    SortedCoordinates again;
    registry.assign(grid, scene, &again, 3);
    EXPECT_EQ(registry.buffer_bytes(), with_scratch);
    EXPECT_TRUE(std::equal(again.x.begin(), again.x.end(), sorted.x.begin(), sorted.x.end()));
  }
}

TEST(CellRegistry, EdgeCases) {
  const CellGrid grid(Box{}, 0.1, CellNumbering::kLinear);
  for (const int threads : {1, 2, 5}) {  // also more threads than particles
    check_registry(grid, Scene{}, threads);
    check_registry(grid, make_scene({{1, 1, 1}}), threads);
    check_registry(grid, make_scene({{0.5, 0.5, 0.5}, {0.5, 0.5, 0.5}, {0.5, 0.5, 0.5}, {1, 1, 1}}),
                   threads);
  }
  CellRegistry registry;
  registry.assign(grid, make_scene({{0.5, 0.5, 0.5}, {0.5, 0.5, 0.5}, {0.5, 0.5, 0.5}, {1, 1, 1}}));
  EXPECT_EQ(registry.max_occupancy, 3u);
  registry.assign(grid, Scene{});
  EXPECT_EQ(registry.max_occupancy, 0u);
  // A sorted copy into coordinates that held something else replaces them entirely.
  SortedCoordinates sorted;
  registry.assign(grid,
                  make_scene({{0.1, 0.1, 0.1}, {0.2, 0.2, 0.2}, {0.3, 0.3, 0.3}, {0.4, 0.4, 0.4}}),
                  &sorted);
  sorted.diameter.assign(4, 1.0);
  registry.assign(grid, make_scene({{0.9, 0.9, 0.9}, {0.05, 0.05, 0.05}}), &sorted);
  EXPECT_EQ(std::vector<double>(sorted.x.begin(), sorted.x.end()),
            (std::vector<double>{0.05, 0.9}));
  EXPECT_TRUE(sorted.diameter.empty());
  // Reassigning with a bigger then a smaller scene leaves no stale entries.
  SceneSpec spec;
  spec.n = 3000;
  registry.assign(grid, generate_scene(spec));
  const Scene small = make_scene({{0.05, 0.05, 0.05}, {0.95, 0.95, 0.95}});
  registry.assign(grid, small);
  EXPECT_EQ(registry.slot_particle.size(), 2u);
  EXPECT_EQ(registry.cell_begin.back(), 2u);
  EXPECT_EQ(registry.max_occupancy, 1u);
}

}  // namespace
}  // namespace contactlab::test
