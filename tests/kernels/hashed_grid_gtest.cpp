// Grids beyond the dense cell table: the hashed index over the occupied cells (cell_index.hpp).
// D = 1e-4 in the unit cube (10^12 cells) and a box 10^4 D long and D thin against the brute
// force; an axis longer than the dense table; a larger scene against an independent
// cell-by-cell reference; the same work as the dense index where both run; the automatic
// choice; and an index whose memory follows N, not the cell count.
#include <gtest/gtest.h>

#include <unordered_map>

#include "contactlab/kernels/error.hpp"
#include "contactlab/kernels/simd.hpp"
#include "test_support.hpp"

namespace contactlab::test {
namespace {

// Sparse scenes with contacts: uniform particles, tight clusters (cubes 4 D wide around random
// centres, clamped into the box) and pairs about D apart along each axis and a diagonal (the
// near-ties the cell widening protects, at random places, so across cell faces too).
Scene sparse_scene(const Box& box, double d, std::size_t uniform, std::size_t clusters,
                   std::size_t per_cluster, std::size_t pairs, std::uint64_t seed) {
  Xoshiro256 rng(seed);
  std::vector<Point> points;
  auto inside = [&](Point p) {
    for (int a = 0; a < 3; ++a) p[a] = std::clamp(p[a], box.lo[a], box.hi[a]);
    return p;
  };
  auto random_point = [&] {
    Point p;
    for (int a = 0; a < 3; ++a) p[a] = box.lo[a] + rng.uniform() * box.extent(a);
    return p;
  };
  for (std::size_t i = 0; i < uniform; ++i) points.push_back(random_point());
  for (std::size_t c = 0; c < clusters; ++c) {
    const Point centre = random_point();
    for (std::size_t k = 0; k < per_cluster; ++k) {
      Point p;
      for (int a = 0; a < 3; ++a) p[a] = centre[a] + (rng.uniform() - 0.5) * 4.0 * d;
      points.push_back(inside(p));
    }
  }
  const double diagonal = d / std::sqrt(3.0);
  const std::array<Point, 4> steps{
      {{d, 0, 0}, {0, d, 0}, {0, 0, d}, {diagonal, diagonal, diagonal}}};
  for (std::size_t i = 0; i < pairs; ++i) {
    const Point p = random_point();
    const Point& step = steps[i % steps.size()];
    points.push_back(p);
    points.push_back(inside({p[0] + step[0], p[1] + step[1], p[2] + step[2]}));
  }
  return make_scene(points, box);
}

Variant with_grid(Variant v, GridIndex grid) {
  v.grid = grid;
  return v;
}

// Runs the covering variants with `grid` against the brute force (float variants too), at 1 and
// 3 threads; the sorted layouts also on the best SIMD
// target forced (sparse scenes otherwise stay in the scalar loop). Each run must use the index
// use_hashed_index names; a dense index the grid cannot hold must be refused.
void expect_matches_brute_force(const Scene& scene, double d, const std::vector<GridIndex>& grids) {
  const ContactList exact = brute_force_contacts(scene, d);
  ASSERT_GT(exact.pair_count(), scene.size() / 4);  // plenty of contacts
  for (const GridIndex grid : grids) {
    for (const Variant& base : covering_variants()) {
      const Variant variant = with_grid(base, grid);
      SCOPED_TRACE(to_string(variant));
      const CellGrid cells(
          scene.box, d,
          variant.order == Order::kMorton ? CellNumbering::kMorton : CellNumbering::kLinear);
      if (grid == GridIndex::kDense && !cells.dense_fits()) {
        EXPECT_THROW(detect(scene, variant, d, 1), InputError);
        continue;
      }
      const bool hashed = use_hashed_index(grid, cells, scene.size());
      const ContactList& want = exact;  // float variants decide near-ties in double
      const std::vector<std::string> targets =
          variant.order == Order::kUnsorted
              ? std::vector<std::string>{"best"}
              : std::vector<std::string>{"best", simd_targets().front()};
      for (const std::string& target : targets) {
        select_simd_target(target);
        for (const int threads : {1, 3}) {
          SCOPED_TRACE("simd=" + target + " threads=" + std::to_string(threads));
          const Detected got = detect(scene, variant, d, threads);
          EXPECT_EQ(got.run.hashed_index, hashed);
          EXPECT_TRUE(same_contacts(got.contacts, want));
          EXPECT_EQ(got.run.contact_pairs, want.pair_count());
        }
      }
      select_simd_target("best");
    }
  }
}

TEST(HashedGrid, TinyDiameterInTheUnitCubeMatchesBruteForce) {
  const double d = 1e-4;
  const CellGrid grid(Box{}, d, CellNumbering::kLinear);
  ASSERT_GT(grid.cell_count(), std::uint64_t{999'000'000'000});  // 9999^3: no dense table
  ASSERT_FALSE(grid.dense_fits());
  const Scene scene = sparse_scene(Box{}, d, 3000, 200, 30, 1500, 11);
  ASSERT_GE(scene.size(), 12'000u);
  ASSERT_TRUE(use_hashed_index(GridIndex::kAuto, grid, scene.size()));
  expect_matches_brute_force(scene, d, {GridIndex::kHashed, GridIndex::kAuto});
}

TEST(HashedGrid, DenseIsRefusedWhereItDoesNotFit) {
  const Scene scene = sparse_scene(Box{}, 1e-4, 100, 0, 0, 0, 3);
  try {
    detect(scene, parse_variant("particle/sorted/static/grid=dense"), 1e-4, 1);
    FAIL() << "a dense index of 10^12 keys was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("grid=dense"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("grid=hashed"), std::string::npos) << e.what();
  }
}

// 10^4 D along x, D across: a single row of cells, every stencil a row of 3. Both indexes run
// with linear keys (10^4 of them; auto keeps the dense table); Morton keys span a cube of 2^42
// and are hashed. The box sits far from the origin (a larger widening).
TEST(HashedGrid, LongThinBoxMatchesBruteForceWithBothIndexes) {
  const double d = 0.5;
  const Box box{{1e5, -3.0, 7.0}, {1e5 + 1e4 * d, -3.0 + d, 7.0 + d}};
  const CellGrid grid(box, d, CellNumbering::kLinear);
  EXPECT_EQ(grid.dims(), (std::array<int, 3>{9999, 1, 1}));
  const Scene scene = sparse_scene(box, d, 8000, 100, 20, 1000, 5);
  EXPECT_FALSE(use_hashed_index(GridIndex::kAuto, grid, scene.size()));
  expect_matches_brute_force(scene, d, {GridIndex::kDense, GridIndex::kHashed, GridIndex::kAuto});
}

// An axis of 3 x 10^8 cells: more keys than a dense table holds, so auto is hashed; Morton
// keys (21 bits an axis) refuse it with a clear message.
TEST(HashedGrid, AxisLongerThanTheDenseTable) {
  const double d = 1.0;
  const Box box{{0, 0, 0}, {3e8, 1, 1}};
  const CellGrid grid(box, d, CellNumbering::kLinear);
  ASSERT_FALSE(grid.dense_fits());
  const Scene scene = sparse_scene(box, d, 500, 200, 8, 1000, 9);
  const ContactList exact = brute_force_contacts(scene, d);
  ASSERT_GT(exact.pair_count(), 1000u);
  for (const Variant& variant : only(covering_variants(), Precision::kDouble)) {
    SCOPED_TRACE(to_string(variant));
    if (variant.order == Order::kMorton) {
      try {
        detect(scene, variant, d, 2);
        FAIL() << "Morton keys of a 3e8-cell axis were accepted";
      } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("Morton"), std::string::npos) << e.what();
      }
      continue;
    }
    const Detected got = detect(scene, variant, d, 2);
    EXPECT_TRUE(got.run.hashed_index);
    EXPECT_TRUE(same_contacts(got.contacts, exact));
  }
}

// The contacts of a scene too large for the brute force, found cell by cell independently of
// the detector: a std::unordered_map from cell coordinates to particles, all 27 neighbours.
ContactList cell_checked_reference(const Scene& scene, double d) {
  const CellGrid grid(scene.box, d, CellNumbering::kLinear);
  auto pack = [](int cx, int cy, int cz) {
    return (std::uint64_t(cz) << 42) | (std::uint64_t(cy) << 21) | std::uint64_t(cx);
  };
  std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> cells;
  std::vector<std::array<int, 3>> at(scene.size());
  for (std::uint32_t i = 0; i < scene.size(); ++i) {
    at[i] = grid.coords_of(scene.x[i], scene.y[i], scene.z[i]);
    cells[pack(at[i][0], at[i][1], at[i][2])].push_back(i);
  }
  ContactList list;
  list.offsets.assign(scene.size() + 1, 0);
  std::vector<std::uint32_t> row;
  for (std::uint32_t i = 0; i < scene.size(); ++i) {
    row.clear();
    for (int dz = -1; dz <= 1; ++dz) {
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          const int cx = at[i][0] + dx, cy = at[i][1] + dy, cz = at[i][2] + dz;
          if (!grid.in_range(cx, cy, cz)) continue;
          const auto found = cells.find(pack(cx, cy, cz));
          if (found == cells.end()) continue;
          for (const std::uint32_t j : found->second) {
            if (j != i && in_contact(scene.x[i] - scene.x[j], scene.y[i] - scene.y[j],
                                     scene.z[i] - scene.z[j], d * d)) {
              row.push_back(j);
            }
          }
        }
      }
    }
    std::sort(row.begin(), row.end());
    list.partners.insert(list.partners.end(), row.begin(), row.end());
    list.offsets[i + 1] = list.partners.size();
  }
  return list;
}

TEST(HashedGrid, LargerSceneMatchesACellCheckedReference) {
  const double d = 1e-4;
  const Scene scene = sparse_scene(Box{}, d, 40'000, 1000, 50, 5000, 21);
  const ContactList want = cell_checked_reference(scene, d);
  ASSERT_GT(want.pair_count(), 50'000u);
  for (const char* text : {"particle/sorted/static", "cell/unsorted/half/dynamic,64",
                           "cell/morton/full/guided,8", "particle/unsorted/half/static,200"}) {
    const Variant variant = parse_variant(text);
    SCOPED_TRACE(text);
    const Detected got = detect(scene, variant, d, 2);
    EXPECT_TRUE(got.run.hashed_index);
    EXPECT_TRUE(same_contacts(got.contacts, want));
  }
}

// Where both run, the hashed index finds the same candidates as the dense one: the same work per
// particle, and per cell the dense loop's occupied cells in the same order.
TEST(HashedGrid, SameWorkAsTheDenseIndex) {
  SceneSpec spec;
  spec.kind = SceneKind::kClustered;
  spec.n = 3000;
  spec.diameter = 0.03;
  spec.seed = 7;
  const Scene scene = generate_scene(spec);
  for (const char* text : {"particle/sorted/full/static", "particle/unsorted/half/dynamic,7",
                           "cell/sorted/full/static", "cell/morton/half/dynamic,7"}) {
    SCOPED_TRACE(text);
    ContactDetector detector;
    DetectOptions options;
    options.diameter = spec.diameter;
    options.threads = 2;
    options.variant = with_grid(parse_variant(text), GridIndex::kDense);
    const LoopWork dense = detector.iteration_work(scene, options);
    const DetectRun dense_run = detector.run(scene, options);
    options.variant.grid = GridIndex::kHashed;
    const LoopWork hashed = detector.iteration_work(scene, options);
    const DetectRun hashed_run = detector.run(scene, options);
    EXPECT_FALSE(dense_run.hashed_index);
    EXPECT_TRUE(hashed_run.hashed_index);
    EXPECT_EQ(hashed_run.candidate_tests, dense_run.candidate_tests);
    EXPECT_EQ(hashed_run.contact_pairs, dense_run.contact_pairs);
    if (options.variant.loop == LoopKind::kParticle) {
      EXPECT_EQ(hashed.tests, dense.tests);
      EXPECT_EQ(hashed.homes, dense.homes);
      EXPECT_EQ(hashed.builds, dense.builds);
    } else {
      LoopWork occupied;
      for (std::size_t k = 0; k < dense.homes.size(); ++k) {
        if (dense.homes[k] == 0) continue;
        occupied.tests.push_back(dense.tests[k]);
        occupied.homes.push_back(dense.homes[k]);
        occupied.builds.push_back(dense.builds[k]);
      }
      EXPECT_EQ(hashed.tests, occupied.tests);
      EXPECT_EQ(hashed.homes, occupied.homes);
      EXPECT_EQ(hashed.builds, occupied.builds);
    }
  }
}

TEST(HashedGrid, AutoChoosesHashedOnlyForGridsFarLargerThanN) {
  const CellGrid paper(Box{}, 1.0 / 200.0, CellNumbering::kLinear);  // 199^3 = 7.9e6 keys
  EXPECT_FALSE(use_hashed_index(GridIndex::kAuto, paper, 1'024'000));
  EXPECT_FALSE(use_hashed_index(GridIndex::kAuto, paper, 10));  // below kDenseKeysAlways
  EXPECT_TRUE(use_hashed_index(GridIndex::kHashed, paper, 1'024'000));
  const CellGrid fine(Box{}, 1.0 / 600.0, CellNumbering::kLinear);  // 599^3 = 2.1e8 keys
  EXPECT_FALSE(use_hashed_index(GridIndex::kAuto, fine, 4'000'000));
  EXPECT_TRUE(use_hashed_index(GridIndex::kAuto, fine, 1'000'000));
  EXPECT_FALSE(use_hashed_index(GridIndex::kDense, fine, 1'000'000));
  const CellGrid huge(Box{}, 1e-4, CellNumbering::kLinear);
  EXPECT_TRUE(use_hashed_index(GridIndex::kAuto, huge, std::size_t{1} << 31));
  EXPECT_THROW(use_hashed_index(GridIndex::kDense, huge, 1), InputError);
}

// The hashed index holds the occupied cells (at most N) and a table of at most 4 entries per
// occupied cell: bytes per particle bounded whatever the grid, 10^9 or 10^12 cells alike.
TEST(HashedGrid, IndexMemoryFollowsParticlesNotCells) {
  const Scene scene = sparse_scene(Box{}, 1e-4, 50'000, 500, 20, 0, 31);
  const double n = static_cast<double>(scene.size());
  std::vector<double> bytes_per_particle;
  for (const double d : {1e-3, 1e-4, 1e-5}) {
    CellRegistry registry;
    const CellGrid grid(Box{}, d, CellNumbering::kLinear);
    registry.assign(grid, scene, nullptr, 2, true);
    EXPECT_LE(registry.occupied.size(), scene.size());
    EXPECT_TRUE(registry.cell_begin.empty());
    // 8 + 4 bytes per occupied cell listed, 16 per table entry, at most 4 entries per cell.
    EXPECT_LE(static_cast<double>(registry.index_bytes()), 80.0 * n) << "D = " << d;
    bytes_per_particle.push_back(static_cast<double>(registry.index_bytes()) / n);
  }
  // 10^9 to 10^15 cells: the index does not grow with the grid.
  EXPECT_LE(bytes_per_particle.back(), 1.5 * bytes_per_particle.front());
}

}  // namespace
}  // namespace contactlab::test
