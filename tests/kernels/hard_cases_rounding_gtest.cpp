// Hard cases of rounding: pairs at D (1 -/+ 1e-12), with per-particle diameters and across cell
// faces; boxes other than the unit cube, far from the origin (the float variants), and long and
// thin (the cell coordinate's own rounding).
#include <gtest/gtest.h>

#include <cmath>

#include "contactlab/kernels/pair_test.hpp"
#include "hard_case_support.hpp"
#include "test_support.hpp"

namespace contactlab::test {
namespace {

// Pairs at D (1 - 1e-12) must be contacts, pairs at D (1 + 1e-12) must not: the relative margin
// 1e-12 is far above double rounding (1e-16), so the classification is unambiguous. Pairs are
// placed on sites 4 D apart (so pairs never meet each other), in random directions and along the
// axes, some straddling cell faces.
struct NearTies {
  Scene scene;
  ContactList expected;
};

NearTies make_near_ties(double d, bool per_particle, std::uint64_t seed) {
  Xoshiro256 rng(seed);
  std::vector<Point> points;
  std::vector<double> diameters;
  Pairs pairs;
  const double site = 4.0 * d;
  const int sites = static_cast<int>(std::floor((1.0 - 2 * d) / site));
  int count = 0;
  for (int k = 0; k < sites && count < 1200; ++k) {
    for (int j = 0; j < sites && count < 1200; ++j) {
      for (int i = 0; i < sites && count < 1200; ++i, ++count) {
        const double di = per_particle ? d * (0.3 + 0.7 * rng.uniform()) : d;
        const double dj = per_particle ? d * (0.3 + 0.7 * rng.uniform()) : d;
        const double reach = per_particle ? 0.5 * (di + dj) : d;
        const bool inside = (count % 2) == 0;
        const double dist = reach * (inside ? 1.0 - 1e-12 : 1.0 + 1e-12);
        // Direction: along an axis for a third of the sites, else random on the sphere.
        double u[3] = {0, 0, 0};
        if (count % 3 == 0) {
          u[(count / 3) % 3] = (count % 2) ? 1.0 : -1.0;
        } else {
          double n2;
          do {
            for (double& c : u) c = 2 * rng.uniform() - 1;
            n2 = u[0] * u[0] + u[1] * u[1] + u[2] * u[2];
          } while (n2 > 1 || n2 < 0.01);
          for (double& c : u) c /= std::sqrt(n2);
        }
        const Point p{d + (i + 0.5) * site, d + (j + 0.5) * site, d + (k + 0.5) * site};
        const Point q{p[0] + dist * u[0], p[1] + dist * u[1], p[2] + dist * u[2]};
        const auto a = static_cast<std::uint32_t>(points.size());
        points.push_back(p);
        points.push_back(q);
        diameters.push_back(di);
        diameters.push_back(dj);
        if (inside) pairs.emplace_back(a, a + 1);
      }
    }
  }
  NearTies result;
  result.scene = make_scene(points);
  if (per_particle) result.scene.diameter = diameters;
  result.expected = list_from_pairs(points.size(), pairs);
  return result;
}

TEST(HardCase, NearTiesAtOnePlusMinusOneETwelve) {
  for (const double d : {1.0 / 200.0, 0.1, 0.03}) {
    SCOPED_TRACE("D = " + std::to_string(d));
    const NearTies ties = make_near_ties(d, false, 1234);
    ASSERT_GE(ties.scene.size(), 16u);
    validate_scene(ties.scene, "near ties");
    // The construction: each pair classifies as intended under eq. (2).
    for (std::uint32_t a = 0; a < ties.scene.size(); a += 2) {
      const bool want = ties.expected.count(a) == 1;
      EXPECT_EQ(
          in_contact(ties.scene.x[a] - ties.scene.x[a + 1], ties.scene.y[a] - ties.scene.y[a + 1],
                     ties.scene.z[a] - ties.scene.z[a + 1], d * d),
          want);
    }
    ASSERT_TRUE(same_contacts(brute_force_contacts(ties.scene, d), ties.expected));
    // Float rounding alone misjudges some of them: the float variants' test in double is needed.
    EXPECT_FALSE(same_contacts(float_brute_force(ties.scene, d), ties.expected));
    if (d < 0.01) {
      expect_variants_match(ties.scene, d, ties.expected, covering_variants(), {2});
    } else {
      expect_variants_match(ties.scene, d, ties.expected, every_variant(), {1, 3});
    }
  }
}

TEST(HardCase, NearTiesWithPerParticleDiameters) {
  for (const double d : {0.02, 0.1}) {
    SCOPED_TRACE("D = " + std::to_string(d));
    const NearTies ties = make_near_ties(d, true, 99);
    ASSERT_TRUE(same_contacts(brute_force_contacts(ties.scene, 0.0), ties.expected));
    EXPECT_FALSE(same_contacts(float_brute_force(ties.scene, 0.0), ties.expected));
    expect_variants_match(ties.scene, 0.0, ties.expected, every_variant());
  }
}

// Axis-aligned near-ties straddling every interior cell face of a 9-cell axis.
TEST(HardCase, NearTiesAcrossCellFaces) {
  const double d = 0.1;
  std::vector<Point> points;
  Pairs pairs;
  for (int c = 1; c < 9; ++c) {
    const double face = c / 9.0;
    for (int axis = 0; axis < 3; ++axis) {
      for (const bool inside : {true, false}) {
        const double dist = d * (inside ? 1.0 - 1e-12 : 1.0 + 1e-12);
        Point p{0.1 + 0.25 * axis, 0.15 + 0.2 * (inside ? 1 : 3), 0.5};
        if (axis == 1) p = {0.7, 0.1 + 0.25 * axis, 0.15 + 0.2 * (inside ? 1 : 3)};
        if (axis == 2) p = {0.15 + 0.2 * (inside ? 1 : 3), 0.9, 0.1 + 0.25 * axis};
        // Put the pair where cell c - 1 meets cell c, offsets chosen per face so pairs of
        // different faces on the same line stay > D apart.
        p[axis] = face - 0.5 * dist;
        Point q = p;
        q[axis] = p[axis] + dist;
        const auto a = static_cast<std::uint32_t>(points.size());
        points.push_back(p);
        points.push_back(q);
        if (inside) pairs.emplace_back(a, a + 1);
      }
    }
  }
  const Scene scene = make_scene(points);
  const ContactList brute = brute_force_contacts(scene, d);
  // The intended pairs are there and the 1 + 1e-12 ones are not (neighbouring faces' pairs may
  // also meet along a line; the brute force decides those).
  for (std::uint32_t a = 0; a < scene.size(); a += 2) {
    const auto row = brute.partners_of(a);
    const bool want =
        std::find(pairs.begin(), pairs.end(), std::make_pair(a, a + 1)) != pairs.end();
    EXPECT_EQ(std::binary_search(row.begin(), row.end(), a + 1), want) << "pair " << a;
  }
  expect_variants_match(scene, d, brute, every_variant());
}

// ----------------------------------------------------------------------------------------------
// Boxes other than the unit cube.

TEST(HardCase, NonUnitBoxes) {
  const std::vector<Box> boxes = {
      Box{{-2.5, 10.0, 1000.0}, {1.5, 12.0, 1003.0}},       // offset, anisotropic
      Box{{1e6, 1e6, -1e6}, {1e6 + 1, 1e6 + 1, -1e6 + 1}},  // far from the origin
      Box{{0, 0, 0}, {10, 0.5, 0.5}},                       // elongated
  };
  for (const Box& box : boxes) {
    for (const auto kind : all_scene_kinds()) {
      SCOPED_TRACE("box " + std::to_string(box.lo[0]) + ".." + std::to_string(box.hi[0]) + ", " +
                   std::string(to_string(kind)));
      SceneSpec spec;
      spec.kind = kind;
      spec.n = 1500;
      spec.box = box;
      spec.seed = 31;
      spec.core = 0.5;
      const double smallest = std::min({box.extent(0), box.extent(1), box.extent(2)});
      spec.diameter = 0.1 * smallest;
      const Scene scene = generate_scene(spec);
      validate_scene(scene, "generated");
      const ContactList brute = brute_force_contacts(scene, spec.diameter);
      ASSERT_GT(brute.pair_count(), 20u);
      expect_variants_match(scene, spec.diameter, brute, covering_variants(), {1, 3});
    }
  }
}

// In a box at 1e6 a float coordinate has a spacing of 1/16: the float variants round x - lo
// (the box's extent sets their band, not its position) and decide the pairs within the band
// in double, so they are exact there too.
TEST(HardCase, FloatVariantsAreExactInABoxFarFromTheOrigin) {
  SceneSpec spec;
  spec.kind = SceneKind::kUniform;
  spec.n = 1500;
  spec.diameter = 0.1;
  spec.seed = 31;
  spec.box = Box{{1e6, 1e6, 1e6}, {1e6 + 1, 1e6 + 1, 1e6 + 1}};
  const Scene scene = generate_scene(spec);
  const ContactList exact = brute_force_contacts(scene, spec.diameter);
  for (const char* variant :
       {"particle/sorted/full/static/float", "cell/unsorted/half/static/float"}) {
    const Detected got = detect(scene, parse_variant(variant), spec.diameter, 1);
    EXPECT_TRUE(same_contacts(got.contacts, exact)) << variant;
  }
}

// One particle far larger than the rest sets the cell width for everyone.
TEST(HardCase, PolydisperseWithOneLargeParticle) {
  SceneSpec spec;
  spec.kind = SceneKind::kPolydisperse;
  spec.n = 2000;
  spec.diameter = 0.03;
  spec.seed = 12;
  Scene scene = generate_scene(spec);
  scene.diameter[777] = 0.4;
  const ContactList brute = brute_force_contacts(scene, 0.0);
  ASSERT_GT(brute.count(777), 20u);
  expect_variants_match(scene, 0.0, brute, covering_variants());
}

// A long thin box [-1, 1] x [0, D] x [0, D] with D just below 2 / 76046, which gives 76046
// cells along x. The pair below is at distance <= D (the brute force reports it, and the pair
// test agrees), yet rounding in (x - lo) * (G / L) puts the two particles two cells apart
// (75347 and 75349), so the 27-cell search cannot find it. cell_grid.hpp promises that the
// 2^-40 widening "keeps the 27-cell search exact"; at this many cells per axis the rounding
// error of the cell coordinate (about G * 2^-53 cells) exceeds the 2^-40 margin.
TEST(HardCase, PairTwoCellsApartInALongThinBox) {
  const double d = 0x1.b93d161df7b12p-16;
  const Box box{{-1.0, 0.0, 0.0}, {1.0, d, d}};
  const Scene scene =
      make_scene({{0x1.f699dee364791p-1, 0.0, 0.0}, {0x1.f69d515d90b4fp-1, 0.0, 0.0}}, box);
  validate_scene(scene, "thin box");
  ASSERT_TRUE(in_contact(scene.x[1] - scene.x[0], 0.0, 0.0, d * d));
  const ContactList expected = list_from_pairs(2, {{0, 1}});
  ASSERT_TRUE(same_contacts(brute_force_contacts(scene, d), expected));
  const CellGrid grid(box, d, CellNumbering::kLinear);
  const int ca = grid.coords_of(scene.x[0], 0.0, 0.0)[0];
  const int cb = grid.coords_of(scene.x[1], 0.0, 0.0)[0];
  EXPECT_LE(cb - ca, 1) << "particles at distance <= D are in cells " << ca << " and " << cb
                        << " of " << grid.dims()[0];
  const Variant linear_variants[] = {parse_variant("cell/sorted/full/static"),
                                     parse_variant("particle/unsorted/half/static")};
  for (const Variant& v : linear_variants) {
    const Detected got = detect(scene, v, d, 1);
    EXPECT_TRUE(same_contacts(got.contacts, expected)) << to_string(v);
  }
}

}  // namespace
}  // namespace contactlab::test
