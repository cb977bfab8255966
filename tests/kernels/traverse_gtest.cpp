// The traversal's other uses and its home range: the half neighbour list (pairs within
// r_i + r_j + skin) against an O(N^2) brute force, and scenes holding ghosts (particles outside
// DetectOptions::homes), which are partners but never homes.
#include <gtest/gtest.h>

#include <string>

#include "contactlab/kernels/error.hpp"
#include "contactlab/kernels/simd.hpp"
#include "test_support.hpp"

namespace contactlab::test {
namespace {

struct Case {
  std::string name;
  Scene scene;
  double diameter;
};

std::vector<Case> cases() {
  std::vector<Case> result;
  SceneSpec spec;
  spec.seed = 20240601;
  spec.kind = SceneKind::kUniform;
  spec.n = 2000;
  spec.diameter = 0.08;
  result.push_back({"uniform", generate_scene(spec), spec.diameter});
  spec.kind = SceneKind::kClustered;
  spec.n = 2500;
  spec.diameter = 0.03;
  spec.core = 0.5;
  spec.background = 0.2;
  result.push_back({"clustered", generate_scene(spec), spec.diameter});
  spec = SceneSpec{};
  spec.seed = 20240601;
  spec.kind = SceneKind::kPolydisperse;
  spec.n = 2000;
  spec.diameter = 0.1;
  spec.size_ratio = 4.0;
  result.push_back({"polydisperse", generate_scene(spec), spec.diameter});
  return result;
}

// Owned ranges: all particles, ghosts after the owned ones, ghosts before them.
std::vector<HomeRange> home_ranges(std::size_t n) {
  const auto u = static_cast<std::uint32_t>(n);
  return {HomeRange{}, HomeRange{0, u - u / 4}, HomeRange{u / 5, u}};
}

std::vector<Variant> double_full_variants() {
  std::vector<Variant> variants = only(covering_variants(), Precision::kDouble);
  std::erase_if(variants, [](const Variant& v) { return v.stencil != Stencil::kFull; });
  return variants;
}

// What ContactDetector::neighbor_list promises, by brute force: for each owned i, every j
// within r_i + r_j + skin that is a ghost or has j > i (the same test expression, in double).
ContactList brute_force_neighbors(const Scene& scene, double diameter, double skin,
                                  HomeRange homes) {
  const std::uint32_t n = static_cast<std::uint32_t>(scene.size());
  const double reach_sq = (diameter + skin) * (diameter + skin);
  ContactList list;
  list.offsets.assign(std::size_t{n} + 1, 0);
  for (std::uint32_t i = 0; i < n; ++i) {
    for (std::uint32_t j = 0; homes.contains(i) && j < n; ++j) {
      if (j == i || !(j > i || !homes.contains(j))) continue;
      const double dx = scene.x[i] - scene.x[j], dy = scene.y[i] - scene.y[j],
                   dz = scene.z[i] - scene.z[j];
      const bool near = scene.has_diameters() ? in_contact(dx, dy, dz, scene.diameter[i] + skin,
                                                           scene.diameter[j] + skin)
                                              : in_contact(dx, dy, dz, reach_sq);
      if (near) list.partners.push_back(j);
    }
    list.offsets[i + 1] = list.partners.size();
  }
  return list;
}

TEST(NeighborList, MatchesBruteForce) {
  for (const Case& c : cases()) {
    const std::size_t contacts = brute_force_contacts(c.scene, c.diameter).pair_count();
    for (const double skin : {0.0, 0.1 * c.diameter}) {
      for (const HomeRange homes : home_ranges(c.scene.size())) {
        const ContactList expected = brute_force_neighbors(c.scene, c.diameter, skin, homes);
        if (skin == 0.0 && homes.covers(static_cast<std::uint32_t>(c.scene.size()))) {
          // Without skin and ghosts: each contact once.
          EXPECT_EQ(expected.partners.size(), contacts) << c.name;
        }
        for (const Variant& v : double_full_variants()) {
          for (const int threads : {1, 2}) {
            SCOPED_TRACE(c.name + " skin " + std::to_string(skin) + " homes [" +
                         std::to_string(homes.first) + ", " + std::to_string(homes.last) + ") " +
                         to_string(v) + " threads " + std::to_string(threads));
            ContactDetector detector;
            DetectOptions options;
            options.variant = v;
            options.diameter = c.diameter;
            options.threads = threads;
            options.homes = homes;
            EXPECT_TRUE(same_contacts(detector.neighbor_list(c.scene, options, skin), expected));
          }
        }
      }
    }
  }
}

TEST(NeighborList, HalfStencilVariantGivesTheSameList) {
  const Case c = cases()[1];
  DetectOptions options;
  options.diameter = c.diameter;
  options.threads = 2;
  options.homes = HomeRange{0, 2000};
  ContactDetector detector;
  const ContactList full = detector.neighbor_list(c.scene, options, 0.1 * c.diameter);
  options.variant.stencil = Stencil::kHalf;
  EXPECT_TRUE(same_contacts(detector.neighbor_list(c.scene, options, 0.1 * c.diameter), full));
}

TEST(NeighborList, RejectsNegativeSkinAndInvertedHomeRange) {
  const Case c = cases()[0];
  ContactDetector detector;
  DetectOptions options;
  options.diameter = c.diameter;
  EXPECT_THROW(detector.neighbor_list(c.scene, options, -0.01), InputError);
  options.homes = HomeRange{10, 5};
  EXPECT_THROW(detector.run(c.scene, options), InputError);
}

// Ghosts in the contact detector. Full stencil: an owned row lists all its contacts, ghosts
// included; a ghost row is empty. Half stencil (see HomeRange): every listed pair is a contact
// with an owned particle, the list stays symmetric, and every owned-owned contact is found.
TEST(Ghosts, AreCandidatesButNeverHomes) {
  for (const Case& c : cases()) {
    const ContactList all = brute_force_contacts(c.scene, c.diameter);
    const std::uint32_t n = static_cast<std::uint32_t>(c.scene.size());
    for (const HomeRange homes : home_ranges(n)) {
      std::uint64_t owned = 0;
      for (std::uint32_t i = 0; i < n; ++i) owned += homes.contains(i);
      for (const Variant& v : only(covering_variants(), Precision::kDouble)) {
        for (const int threads : {1, 2}) {
          SCOPED_TRACE(c.name + " homes [" + std::to_string(homes.first) + ", " +
                       std::to_string(homes.last) + ") " + to_string(v) + " threads " +
                       std::to_string(threads));
          ContactDetector detector;
          DetectOptions options;
          options.variant = v;
          options.diameter = c.diameter;
          options.threads = threads;
          options.homes = homes;
          const DetectRun run = detector.run(c.scene, options);
          const ContactList got = detector.canonical_contacts();
          ASSERT_EQ(got.particle_count(), n);
          // iteration_work visits the same homes and counts the same tests.
          const LoopWork work = detector.iteration_work(c.scene, options);
          std::uint64_t tests = 0, visited = 0;
          for (std::size_t k = 0; k < work.tests.size(); ++k) {
            tests += work.tests[k];
            visited += work.homes[k];
          }
          EXPECT_EQ(tests, run.candidate_tests);
          EXPECT_EQ(visited, owned);
          if (v.stencil == Stencil::kFull) {
            for (std::uint32_t i = 0; i < n; ++i) {
              const auto row = got.partners_of(i);
              const auto want =
                  homes.contains(i) ? all.partners_of(i) : all.partners_of(i).first(0);
              ASSERT_TRUE(std::equal(row.begin(), row.end(), want.begin(), want.end()))
                  << "row " << i << ": " << row_text(got, i);
            }
            continue;
          }
          EXPECT_TRUE(well_formed(got));
          for (std::uint32_t i = 0; i < n; ++i) {
            const auto row = got.partners_of(i);
            const auto want = all.partners_of(i);
            for (const std::uint32_t j : row) {
              ASSERT_TRUE(std::binary_search(want.begin(), want.end(), j)) << i << "-" << j;
              ASSERT_TRUE(homes.contains(i) || homes.contains(j)) << i << "-" << j;
            }
            if (!homes.contains(i)) continue;
            for (const std::uint32_t j : want) {
              if (homes.contains(j)) {
                ASSERT_TRUE(std::binary_search(row.begin(), row.end(), j)) << i << "-" << j;
              }
            }
          }
        }
      }
    }
  }
}

// Where homes are tested in blocks on SIMD lanes, a sparse cell and the occupied cells after it
// along x (up to traversal::kTileCells, at most simd::kBlockHomes particles) share one range
// build as a tile, with rows a cell longer per cell joined. On rows of cells holding 0 to 3
// particles with gaps of 0 to 7 cells, the last cells of the grid's rows among them: the tiles
// form (fewer builds than occupied cells), every row is the scalar loop's entry for entry (same
// partners, same order), and the contacts are the brute force's, with the dense and the hashed
// index, both stencils, double and float.
TEST(Tiles, SparseCellsAlongXShareRangesAndKeepEveryRow) {
  const double diameter = 0.1;  // 10 cells along each axis
  Xoshiro256 rng(31);
  std::vector<Point> points;
  for (int row = 0; row < 60; ++row) {
    const double y = rng.uniform(), z = rng.uniform();
    for (int cell = static_cast<int>(rng.uniform() * 3); cell < 10;
         cell += 1 + static_cast<int>(rng.uniform() * 8)) {
      const int count = 1 + static_cast<int>(rng.uniform() * 3);
      for (int k = 0; k < count; ++k) {
        // Near the row's line, so that neighbours along x and across rows touch.
        points.push_back({(cell + rng.uniform()) * diameter,
                          std::min(1.0, y + 0.3 * diameter * rng.uniform()),
                          std::min(1.0, z + 0.3 * diameter * rng.uniform())});
      }
    }
    points.push_back({1.0, y, z});  // on the box's upper face: the last cell of the row
  }
  const Scene scene = make_scene(points);
  const ContactList expected = brute_force_contacts(scene, diameter);
  ASSERT_GT(expected.pair_count(), 100u);

  auto detect_with = [&](const std::string& target, const std::string& variant, int threads,
                         std::size_t* builds) {
    select_simd_target(target);
    ContactDetector detector;
    DetectOptions options;
    options.variant = parse_variant(variant);
    options.diameter = diameter;
    options.threads = threads;
    detector.run(scene, options);
    const LoopWork work = detector.iteration_work(scene, options);
    *builds = static_cast<std::size_t>(std::count(work.builds.begin(), work.builds.end(), 1));
    return std::pair{detector.contacts(), detector.canonical_contacts()};
  };
  for (const std::string& target : simd_targets()) {
    if (target == "off") continue;
    for (const char* variant :
         {"particle/sorted/full/static", "particle/sorted/half/static",
          "particle/sorted/full/dynamic,5/float", "particle/sorted/half/static/float",
          "particle/sorted/full/static/grid=hashed", "particle/sorted/half/static/grid=hashed"}) {
      for (const int threads : {1, 2}) {
        SCOPED_TRACE(target + " " + variant + " threads=" + std::to_string(threads));
        std::size_t cells = 0, tiles = 0;
        const auto [scalar, scalar_canonical] = detect_with("off", variant, threads, &cells);
        const auto [lanes, lanes_canonical] = detect_with(target, variant, threads, &tiles);
        EXPECT_LT(tiles, cells * 9 / 10);
        EXPECT_TRUE(lanes.offsets == scalar.offsets);
        EXPECT_TRUE(lanes.partners == scalar.partners);
        EXPECT_TRUE(same_contacts(lanes_canonical, expected));
      }
    }
  }
  select_simd_target("best");
}

}  // namespace
}  // namespace contactlab::test
