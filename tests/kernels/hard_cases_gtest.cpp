// Named hard cases for contact detection: exact ties on lattices, particles on cell faces and on
// the box's upper faces, coincident particles, everything in one cell, D larger than the box,
// N = 0 and 1. Rounding at D and in the cell coordinate: hard_cases_rounding_gtest.cpp.
//
// Each case states its expected contacts independently where it can (lattice neighbours,
// complete graphs), checks the brute force agrees, then runs the variants against them.
#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "hard_case_support.hpp"
#include "test_support.hpp"

namespace contactlab::test {
namespace {

// ----------------------------------------------------------------------------------------------
// Exact ties on lattices.

// Lattice points lo + (i, j, k) * spacing for i, j, k in `indices`; with a dyadic spacing and lo
// every coordinate and every difference is exact, so axis neighbours are at distance exactly D
// and must all be contacts (touching counts), diagonal neighbours (D sqrt 2) never.
struct Lattice {
  Scene scene;
  std::vector<std::array<int, 3>> index;
  ContactList expected;           // the axis neighbours
  std::vector<int> present_axis;  // how many of each point's 6 axis neighbours are in the set
};

Lattice make_lattice(const Box& box, double spacing, const std::vector<int>& indices) {
  Lattice lattice;
  std::vector<Point> points;
  std::map<std::array<int, 3>, std::uint32_t> id;
  for (const int k : indices) {
    for (const int j : indices) {
      for (const int i : indices) {
        id[{i, j, k}] = static_cast<std::uint32_t>(points.size());
        lattice.index.push_back({i, j, k});
        points.push_back(
            {box.lo[0] + i * spacing, box.lo[1] + j * spacing, box.lo[2] + k * spacing});
      }
    }
  }
  lattice.scene = make_scene(points, box);
  Pairs pairs;
  lattice.present_axis.assign(points.size(), 0);
  for (std::uint32_t a = 0; a < points.size(); ++a) {
    for (int axis = 0; axis < 3; ++axis) {
      for (const int step : {-1, 1}) {
        auto n = lattice.index[a];
        n[axis] += step;
        const auto it = id.find(n);
        if (it == id.end()) continue;
        ++lattice.present_axis[a];
        if (a < it->second) pairs.emplace_back(a, it->second);
      }
    }
  }
  lattice.expected = list_from_pairs(points.size(), pairs);
  return lattice;
}

void check_lattice(const Lattice& lattice, double d, const std::vector<Variant>& variants,
                   const std::vector<int>& threads) {
  const Scene& scene = lattice.scene;
  validate_scene(scene, "lattice");
  // The construction really is exact: every axis neighbour difference is D to the bit.
  for (std::uint32_t a = 0; a < scene.size(); ++a) {
    for (const std::uint32_t b : lattice.expected.partners_of(a)) {
      const double dist = std::abs(scene.x[a] - scene.x[b]) + std::abs(scene.y[a] - scene.y[b]) +
                          std::abs(scene.z[a] - scene.z[b]);
      ASSERT_EQ(dist, d) << "lattice construction is not exact";
    }
  }
  // Interior points have degree exactly 6, every point as many as it has axis neighbours.
  int interior = 0;
  for (std::uint32_t a = 0; a < scene.size(); ++a) {
    ASSERT_EQ(static_cast<int>(lattice.expected.count(a)), lattice.present_axis[a]);
    if (lattice.present_axis[a] == 6) ++interior;
  }
  ASSERT_GT(interior, 0);
  const ContactList brute = brute_force_contacts(scene, d);
  ASSERT_TRUE(same_contacts(brute, lattice.expected)) << "brute force disagrees with the lattice";
  for (std::uint32_t a = 0; a < scene.size(); ++a) {
    if (lattice.present_axis[a] == 6) {
      ASSERT_EQ(brute.count(a), 6u) << "interior point " << a;
    }
  }
  expect_variants_match(scene, d, lattice.expected, variants, threads);
}

// D = 1/200 rounded to the dyadic 41/8192 = 0.0050048828125, so that the lattice is exact.
// It gives the same grid as 1/200 (199 cells per axis); a block of the lattice near each end
// of each axis and in the middle keeps N at 2197.
TEST(HardCase, LatticeTiesNearOneTwoHundredth) {
  const double d = 41.0 / 8192.0;
  ASSERT_EQ(CellGrid(Box{}, d, CellNumbering::kLinear).dims(), (std::array<int, 3>{199, 199, 199}));
  ASSERT_EQ(CellGrid(Box{}, 1.0 / 200.0, CellNumbering::kLinear).dims(),
            (std::array<int, 3>{199, 199, 199}));
  const Lattice lattice =
      make_lattice(Box{}, d, {0, 1, 2, 3, 97, 98, 99, 100, 101, 196, 197, 198, 199});
  check_lattice(lattice, d, covering_variants(), {2});
}

// D = 0.1 rounded up to the dyadic 3277/32768 = 0.100006103515625 (the same 9 cells per axis as
// 0.1): the whole 10 x 10 x 10 lattice, every variant.
TEST(HardCase, LatticeTiesNearOneTenth) {
  const double d = 3277.0 / 32768.0;
  ASSERT_EQ(CellGrid(Box{}, d, CellNumbering::kLinear).dims(), (std::array<int, 3>{9, 9, 9}));
  ASSERT_EQ(CellGrid(Box{}, 0.1, CellNumbering::kLinear).dims(), (std::array<int, 3>{9, 9, 9}));
  const Lattice lattice = make_lattice(Box{}, d, {0, 1, 2, 3, 4, 5, 6, 7, 8, 9});
  check_lattice(lattice, d, every_variant(), {1, 2, 3});
}

// The case the 2^-40 widening of the cell width exists for: the box is exactly 32 D wide, so
// cells of width exactly D would put lattice planes on cell faces where floor(x / w) may round
// either way (the widening makes it 31 cells). The lattice reaches the box's upper faces (x, y
// or z = 1.0 exactly).
TEST(HardCase, LatticeTiesWhenTheBoxIsAWholeNumberOfDiameters) {
  const double d = 1.0 / 32.0;
  ASSERT_EQ(CellGrid(Box{}, d, CellNumbering::kLinear).dims(), (std::array<int, 3>{31, 31, 31}));
  const Lattice lattice = make_lattice(Box{}, d, {0, 1, 2, 3, 15, 16, 17, 29, 30, 31, 32});
  ASSERT_EQ(lattice.scene.x.back(), 1.0);
  check_lattice(lattice, d, every_variant(), {2});
}

// The same in a box that is not the unit cube and not at the origin: 40 D on every axis.
TEST(HardCase, LatticeTiesInAnOffsetBox) {
  const double d = 41.0 / 1024.0;
  const Box box{{-3.0, 10.0, 0.5}, {-3.0 + 40 * d, 10.0 + 40 * d, 0.5 + 40 * d}};
  ASSERT_EQ(CellGrid(box, d, CellNumbering::kLinear).dims(), (std::array<int, 3>{39, 39, 39}));
  const Lattice lattice = make_lattice(box, d, {0, 1, 2, 19, 20, 21, 38, 39, 40});
  ASSERT_EQ(lattice.scene.z.back(), box.hi[2]);
  check_lattice(lattice, d, covering_variants(), {1, 3});
}

// D = 1/200 and 0.1 as the doubles nearest them: multiples i * D are rounded, so whether two
// neighbours touch depends on the last bit; every variant must still round exactly like the
// brute force (they share pair_test.hpp).
TEST(HardCase, LatticeOfRoundedMultiplesMatchesBruteForce) {
  for (const double d : {1.0 / 200.0, 0.1}) {
    SCOPED_TRACE("D = " + std::to_string(d));
    std::vector<int> indices;
    if (d < 0.05) {
      indices = {0, 1, 2, 3, 4, 5, 60, 61, 62, 63, 64, 65, 66, 194, 195, 196, 197, 198, 199, 200};
    } else {
      indices = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10};
    }
    std::vector<Point> points;
    for (const int k : indices) {
      for (const int j : indices) {
        for (const int i : indices)
          points.push_back({std::min(1.0, i * d), std::min(1.0, j * d), std::min(1.0, k * d)});
      }
    }
    const Scene scene = make_scene(points);
    const ContactList brute = brute_force_contacts(scene, d);
    ASSERT_TRUE(well_formed(brute));
    ASSERT_GT(brute.pair_count(), 0u);
    expect_variants_match(scene, d, brute, covering_variants(), {2});
  }
}

// ----------------------------------------------------------------------------------------------
// Faces.

// D = 0.125 gives 7 cells of width 1/7 per axis. Particles sit on the interior cell faces
// x = c / 7 (as rounded), each with a partner across the face at 0.999 D (contact) and another
// across at 1.001 D (none); likewise on y and z faces.
TEST(HardCase, ParticlesOnCellFaces) {
  const double d = 0.125;
  const CellGrid grid(Box{}, d, CellNumbering::kLinear);
  ASSERT_EQ(grid.dims(), (std::array<int, 3>{7, 7, 7}));
  std::vector<Point> points;
  Pairs pairs;
  // Sites are 0.3 apart in the two free coordinates, so particles of different sites never touch.
  for (int axis = 0; axis < 3; ++axis) {
    for (int c = 1; c < 7; ++c) {
      const double face = c / 7.0;
      for (const double u : {0.05, 0.35, 0.65, 0.95}) {
        for (const double v : {0.05, 0.35, 0.65, 0.95}) {
          if (axis > 0 && (c % 2 == 0)) continue;  // keep sites of different axes apart
          auto at = [&](double along) {
            Point p{};
            p[axis] = along;
            p[(axis + 1) % 3] = u;
            p[(axis + 2) % 3] = v;
            return p;
          };
          const auto on = static_cast<std::uint32_t>(points.size());
          points.push_back(at(face));
          const double side = (c % 2 == 0) ? -1.0 : 1.0;
          points.push_back(at(face + side * 0.999 * d));
          pairs.emplace_back(on, on + 1);
          points.push_back(at(face - side * 1.001 * d));
        }
      }
    }
  }
  const Scene scene = make_scene(points);
  // Sites of different faces and axes can still meet; let the brute force be the judge, but
  // make sure the construction's intended pairs are all in it and none of the 1.001 D ones.
  const ContactList brute = brute_force_contacts(scene, d);
  for (const auto& [a, b] : pairs) {
    const auto row = brute.partners_of(a);
    ASSERT_TRUE(std::binary_search(row.begin(), row.end(), b)) << a << "-" << b;
    const auto far = brute.partners_of(a);
    ASSERT_FALSE(std::binary_search(far.begin(), far.end(), b + 1)) << a << "-" << b + 1;
  }
  expect_variants_match(scene, d, brute, every_variant());
}

// Particles exactly on the upper faces x = 1, y = 1, z = 1 (faces, edges, the corner), which
// belong to the last cell, with neighbours inside the box and across the lower cells.
TEST(HardCase, ParticlesOnTheUpperFacesOfTheBox) {
  const double d = 0.1;  // 9 cells per axis: the last cell is [8/9, 1]
  std::vector<Point> points = {
      {1.0, 1.0, 1.0}, {1.0, 1.0, 0.95},  {1.0, 0.95, 1.0}, {0.95, 1.0, 1.0},  // corner + 3
      {1.0, 0.5, 0.5}, {0.92, 0.5, 0.5},  {0.9, 0.5, 0.5},  {0.88, 0.5, 0.5},  // x face
      {0.5, 1.0, 0.5}, {0.5, 0.9, 0.5},   {0.5, 0.85, 0.5},                    // y face
      {0.5, 0.5, 1.0}, {0.5, 0.5, 0.9},   {0.5, 0.5, 0.8},                     // z face
      {1.0, 1.0, 0.3}, {0.93, 0.93, 0.3}, {1.0, 0.9, 0.3},  {0.9, 1.0, 0.3},   // an edge
      {1.0, 0.0, 0.0}, {0.9, 0.0, 0.0},   {1.0, 0.1, 0.0},  {1.0, 0.0, 1.0},   // lower corners
      {0.0, 1.0, 1.0}, {0.1, 1.0, 1.0},   {0.0, 0.0, 1.0},  {0.0, 0.1, 1.0},
  };
  const Scene scene = make_scene(points);
  validate_scene(scene, "upper faces");
  const ContactList brute = brute_force_contacts(scene, d);
  // A few contacts that must be there: the corner with its three neighbours, touching pairs.
  for (const auto& [a, b] :
       Pairs{{0, 1}, {0, 2}, {0, 3}, {4, 5}, {4, 6}, {8, 9}, {11, 12}, {14, 15}}) {
    const auto row = brute.partners_of(a);
    ASSERT_TRUE(std::binary_search(row.begin(), row.end(), b)) << a << "-" << b;
  }
  expect_variants_match(scene, d, brute, every_variant());
}

// ----------------------------------------------------------------------------------------------
// Degenerate populations.

// Many particles at one point are all in contact with each other (distance 0), including a
// pile on the box's upper corner and one on the lower corner.
TEST(HardCase, CoincidentParticles) {
  const double d = 0.05;
  std::vector<Point> points;
  Pairs pairs;
  auto pile = [&](Point p, int count) {
    const auto first = static_cast<std::uint32_t>(points.size());
    for (int k = 0; k < count; ++k) points.push_back(p);
    for (std::uint32_t a = first; a < points.size(); ++a) {
      for (std::uint32_t b = a + 1; b < points.size(); ++b) pairs.emplace_back(a, b);
    }
  };
  pile({0.3, 0.3, 0.3}, 300);
  pile({1.0, 1.0, 1.0}, 150);
  pile({0.0, 0.0, 0.0}, 80);
  pile({0.7, 0.2, 0.9}, 2);
  pile({0.5, 0.5, 0.5}, 1);
  const Scene scene = make_scene(points);
  const ContactList expected = list_from_pairs(points.size(), pairs);
  ASSERT_EQ(expected.pair_count(), 300u * 299 / 2 + 150u * 149 / 2 + 80u * 79 / 2 + 1);
  ASSERT_TRUE(same_contacts(brute_force_contacts(scene, d), expected));
  expect_variants_match(scene, d, expected, every_variant(), {2});

  // The same with per-particle diameters.
  Scene poly = scene;
  poly.diameter.assign(poly.size(), 0.0);
  for (std::size_t i = 0; i < poly.size(); ++i) poly.diameter[i] = 0.01 + 0.001 * double(i % 7);
  ASSERT_TRUE(same_contacts(brute_force_contacts(poly, 0.0), expected));
  expect_variants_match(poly, 0.0, expected, covering_variants());
}

// Every particle in the same cell of a 19^3 grid: the own-cell search does all the work.
TEST(HardCase, AllParticlesInOneCell) {
  const double d = 0.05;
  const CellGrid grid(Box{}, d, CellNumbering::kLinear);
  ASSERT_EQ(grid.dims()[0], 19);
  // Cell 9 on each axis spans [9/19, 10/19) = [0.4736.., 0.5263..).
  Xoshiro256 rng(77);
  std::vector<Point> points;
  points.reserve(400);
  for (int k = 0; k < 400; ++k) {
    points.push_back(
        {0.48 + 0.04 * rng.uniform(), 0.48 + 0.04 * rng.uniform(), 0.48 + 0.04 * rng.uniform()});
  }
  const Scene scene = make_scene(points);
  for (std::size_t i = 0; i < scene.size(); ++i) {
    ASSERT_EQ(grid.coords_of(scene.x[i], scene.y[i], scene.z[i]), (std::array<int, 3>{9, 9, 9}));
  }
  const ContactList brute = brute_force_contacts(scene, d);
  ASSERT_GT(brute.pair_count(), 1000u);
  ASSERT_LT(brute.pair_count(), 400u * 399 / 2);  // not all: the cube's diagonal exceeds D
  expect_variants_match(scene, d, brute, every_variant(), {2});
  for (const Variant& v : covering_variants()) {
    const Detected got = detect(scene, v, d, 2);
    EXPECT_EQ(got.run.max_cell_occupancy, 400u);
    EXPECT_EQ(got.run.candidate_tests, v.stencil == Stencil::kFull ? 400u * 399 : 400u * 399 / 2);
  }
}

// D larger than the box: one cell (G = 1) holds everything.
TEST(HardCase, DiameterLargerThanTheBox) {
  SceneSpec spec;
  spec.kind = SceneKind::kUniform;
  spec.n = 200;
  spec.seed = 8;
  const Scene scene = generate_scene(spec);
  // D = 2 > sqrt(3): every pair touches.
  {
    const double d = 2.0;
    ASSERT_EQ(CellGrid(Box{}, d, CellNumbering::kLinear).dims(), (std::array<int, 3>{1, 1, 1}));
    Pairs all;
    for (std::uint32_t a = 0; a < 200; ++a) {
      for (std::uint32_t b = a + 1; b < 200; ++b) all.emplace_back(a, b);
    }
    const ContactList expected = list_from_pairs(200, all);
    ASSERT_TRUE(same_contacts(brute_force_contacts(scene, d), expected));
    expect_variants_match(scene, d, expected, every_variant());
    const Detected got = detect(scene, Variant{}, d, 2);
    EXPECT_EQ(got.run.grid_dims, (std::array<int, 3>{1, 1, 1}));
    EXPECT_EQ(got.run.max_cell_occupancy, 200u);
  }
  // D = 1.2 and D = 1 (exactly the box): one cell, but not every pair touches.
  for (const double d : {1.2, 1.0}) {
    SCOPED_TRACE("D = " + std::to_string(d));
    ASSERT_EQ(CellGrid(Box{}, d, CellNumbering::kLinear).dims(), (std::array<int, 3>{1, 1, 1}));
    const ContactList brute = brute_force_contacts(scene, d);
    ASSERT_LT(brute.pair_count(), 200u * 199 / 2);
    expect_variants_match(scene, d, brute, covering_variants());
  }
  // Corners joined by edges of the box (length exactly 1 = D: touching); face and space
  // diagonals (sqrt 2, sqrt 3) are too long.
  const Scene corners = make_scene({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {1, 1, 1}});
  const ContactList expected = list_from_pairs(4, {{0, 1}, {1, 2}, {2, 3}});
  ASSERT_TRUE(same_contacts(brute_force_contacts(corners, 1.0), expected));
  expect_variants_match(corners, 1.0, expected, every_variant());
}

TEST(HardCase, EmptyScene) {
  const Scene scene;
  for (const Variant& v : every_variant()) {
    for (const int t : {1, 2, 3}) {
      const Detected got = detect(scene, v, 0.1, t);
      EXPECT_EQ(got.contacts.particle_count(), 0u) << to_string(v);
      EXPECT_TRUE(got.contacts.partners.empty());
      EXPECT_EQ(got.run.contact_pairs, 0u);
      EXPECT_EQ(got.run.candidate_tests, 0u);
      EXPECT_EQ(got.run.max_cell_occupancy, 0u);
    }
  }
  EXPECT_EQ(brute_force_contacts(scene, 0.1), ContactList{});
}

TEST(HardCase, SingleParticle) {
  for (const Point p : {Point{0.5, 0.5, 0.5}, Point{1.0, 1.0, 1.0}, Point{0.0, 0.0, 0.0}}) {
    const Scene scene = make_scene({p});
    for (const Variant& v : every_variant()) {
      for (const int t : {1, 2, 3}) {
        const Detected got = detect(scene, v, 0.1, t);
        EXPECT_EQ(got.contacts.particle_count(), 1u) << to_string(v);
        EXPECT_TRUE(got.contacts.partners.empty());
        EXPECT_EQ(got.run.contact_pairs, 0u);
        EXPECT_EQ(got.run.candidate_tests, 0u);
        EXPECT_EQ(got.run.max_cell_occupancy, 1u);
      }
    }
  }
}

}  // namespace
}  // namespace contactlab::test
