// ContactDetector's interface: option validation, the DetectRun fields, working ids, the
// observer hooks, and reuse of one detector across runs of different sizes and variants.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <mutex>
#include <set>

#include "contactlab/kernels/error.hpp"
#include "contactlab/kernels/simd.hpp"
#include "test_support.hpp"

namespace contactlab::test {
namespace {

Scene uniform_scene(std::uint64_t n, double d, std::uint64_t seed) {
  SceneSpec spec;
  spec.kind = SceneKind::kUniform;
  spec.n = n;
  spec.diameter = d;
  spec.seed = seed;
  return generate_scene(spec);
}

TEST(Detector, RejectsNonPositiveOrNonFiniteDiameter) {
  const Scene scene = uniform_scene(10, 0.1, 1);
  ContactDetector detector;
  for (const double d : {0.0, -0.1, std::numeric_limits<double>::quiet_NaN(),
                         std::numeric_limits<double>::infinity()}) {
    DetectOptions options;
    options.diameter = d;
    EXPECT_THROW(detector.run(scene, options), InputError) << "D = " << d;
  }
}

TEST(Detector, RejectsInvalidSchedules) {
  const Scene scene = uniform_scene(10, 0.1, 1);
  ContactDetector detector;
  for (const Schedule bad :
       {Schedule{ScheduleKind::kDynamic, 0}, Schedule{ScheduleKind::kGuided, 0},
        Schedule{ScheduleKind::kStatic, -1}, Schedule{ScheduleKind::kDynamic, -5}}) {
    DetectOptions options;
    options.diameter = 0.1;
    options.variant.schedule = bad;
    EXPECT_THROW(detector.run(scene, options), InputError) << to_string(bad);
  }
}

TEST(Detector, PerParticleDiametersOverrideTheScalarDiameter) {
  SceneSpec spec;
  spec.kind = SceneKind::kPolydisperse;
  spec.n = 800;
  spec.diameter = 0.15;
  spec.seed = 3;
  const Scene scene = generate_scene(spec);
  const ContactList expected = brute_force_contacts(scene, 0.0);
  ASSERT_GT(expected.pair_count(), 100u);
  // D = 0 would be rejected for a scene without diameters; here it is ignored.
  for (const double d : {0.0, 0.01, 0.5}) {
    const Detected got = detect(scene, Variant{}, d, 2);
    EXPECT_TRUE(same_contacts(got.contacts, expected)) << "D = " << d;
    // The grid is built for the largest diameter.
    EXPECT_EQ(got.run.grid_dims,
              CellGrid(scene.box, scene.max_diameter(), CellNumbering::kLinear).dims());
  }
}

TEST(Detector, RunReportsItsShape) {
  const Scene scene = uniform_scene(1500, 0.1, 5);
  const CellGrid grid(scene.box, 0.1, CellNumbering::kLinear);
  CellRegistry registry;
  registry.assign(grid, scene);
  for (const int threads : {1, 2, 3}) {
    const Detected d = detect(scene, Variant{}, 0.1, threads);
    EXPECT_EQ(d.run.threads, threads);
    EXPECT_EQ(d.run.thread_busy_s.size(), static_cast<std::size_t>(threads));
    for (const double busy : d.run.thread_busy_s) EXPECT_GE(busy, 0.0);
    EXPECT_GE(d.run.setup_s, 0.0);
    EXPECT_GE(d.run.detect_s, 0.0);
    EXPECT_DOUBLE_EQ(d.run.total_s(), d.run.setup_s + d.run.detect_s);
    EXPECT_EQ(d.run.grid_dims, grid.dims());
    EXPECT_EQ(d.run.max_cell_occupancy, registry.max_occupancy);
    EXPECT_EQ(d.run.contact_pairs, d.contacts.pair_count());
  }
  // threads = 0: OpenMP's default, at least one.
  const Detected d = detect(scene, Variant{}, 0.1, 0);
  EXPECT_GE(d.run.threads, 1);
  EXPECT_EQ(d.run.thread_busy_s.size(), static_cast<std::size_t>(d.run.threads));
}

TEST(Detector, WorkingIdsMapBackToInputRows) {
  const Scene scene = uniform_scene(1200, 0.1, 9);
  const ContactList expected = brute_force_contacts(scene, 0.1);
  for (const auto order : {Order::kUnsorted, Order::kSorted, Order::kMorton}) {
    SCOPED_TRACE(std::string(to_string(order)));
    ContactDetector detector;
    DetectOptions options;
    options.diameter = 0.1;
    options.threads = 2;
    options.variant.order = order;
    detector.run(scene, options);
    const auto map = detector.working_to_input();
    if (order == Order::kUnsorted) {
      EXPECT_TRUE(map.empty());
    } else {
      ASSERT_EQ(map.size(), scene.size());
      std::vector<std::uint32_t> sorted(map.begin(), map.end());
      std::sort(sorted.begin(), sorted.end());
      for (std::size_t i = 0; i < sorted.size(); ++i)
        ASSERT_EQ(sorted[i], i) << "not a permutation";
    }
    EXPECT_EQ(detector.contacts().particle_count(), scene.size());
    EXPECT_EQ(detector.contacts().pair_count(), expected.pair_count());
    EXPECT_TRUE(same_contacts(canonicalize(detector.contacts(), map), expected));
    // On a given team (the DEM rebuild's own thread count), the same list.
    EXPECT_EQ(canonicalize(detector.contacts(), map, 1), canonicalize(detector.contacts(), map));
    EXPECT_EQ(canonicalize(detector.contacts(), map, 3), canonicalize(detector.contacts(), map));
    EXPECT_TRUE(same_contacts(detector.canonical_contacts(), expected));
  }
}

// iteration_work: the pair tests, home particles and neighbour-range builds of each iteration
// of the parallel loop, in loop order.
TEST(Detector, IterationWorkIsWhatEachIterationDoes) {
  SceneSpec spec;
  spec.kind = SceneKind::kBlobs;
  spec.n = 3000;
  spec.diameter = 0.04;
  spec.seed = 21;
  for (const bool poly : {false, true}) {
    if (poly) spec.kind = SceneKind::kPolydisperse;
    const Scene scene = generate_scene(spec);
    const auto per_particle = expected_full_candidates_per_particle(scene, spec.diameter);
    const TiledCandidates tiled = expected_tiled_candidates(scene, spec.diameter);
    for (const Variant& v : covering_variants()) {
      SCOPED_TRACE(to_string(v) + (poly ? " polydisperse" : ""));
      ContactDetector detector;
      DetectOptions options;
      options.variant = v;
      options.diameter = spec.diameter;
      options.threads = 2;
      const LoopWork loop = detector.iteration_work(scene, options);
      const std::vector<std::uint32_t>& work = loop.tests;
      const DetectRun run = detector.run(scene, options);
      std::uint64_t sum = 0;
      for (const auto w : work) sum += w;
      EXPECT_EQ(sum, run.candidate_tests);
      ASSERT_EQ(loop.homes.size(), work.size());
      ASSERT_EQ(loop.builds.size(), work.size());
      std::uint64_t homes = 0, builds = 0;
      for (std::size_t i = 0; i < work.size(); ++i) {
        homes += loop.homes[i];
        builds += loop.builds[i];
      }
      EXPECT_EQ(homes, scene.size());
      const CellGrid grid(
          scene.box, poly ? scene.max_diameter() : spec.diameter,
          v.order == Order::kMorton ? CellNumbering::kMorton : CellNumbering::kLinear);
      std::set<std::uint32_t> occupied;
      for (std::size_t i = 0; i < scene.size(); ++i) {
        const auto c = grid.coords_of(scene.x[i], scene.y[i], scene.z[i]);
        occupied.insert(grid.key(c[0], c[1], c[2]));
      }
      if (v.loop == LoopKind::kCell) {
        ASSERT_EQ(work.size(), grid.key_count());
        // Every occupied cell builds its ranges once, and only those.
        EXPECT_EQ(builds, occupied.size());
        for (std::size_t k = 0; k < work.size(); ++k) {
          ASSERT_EQ(loop.builds[k], loop.homes[k] > 0 ? 1 : 0) << "key " << k;
        }
        if (v.stencil == Stencil::kFull) {
          std::vector<std::uint64_t> per_key(grid.key_count(), 0);
          for (std::size_t i = 0; i < scene.size(); ++i) {
            const auto c = grid.coords_of(scene.x[i], scene.y[i], scene.z[i]);
            per_key[grid.key(c[0], c[1], c[2])] += per_particle[i];
          }
          for (std::size_t k = 0; k < work.size(); ++k)
            ASSERT_EQ(work[k], per_key[k]) << "key " << k;
        }
      } else {
        ASSERT_EQ(work.size(), scene.size());
        EXPECT_TRUE(std::all_of(loop.homes.begin(), loop.homes.end(),
                                [](std::uint32_t h) { return h == 1; }));
        // In cell order the particles of a cell are consecutive: one build per occupied cell,
        // or per tile. In input order almost every particle starts a new cell.
        if (run.tiled) {
          EXPECT_EQ(builds, tiled.tiles);
          EXPECT_LT(builds, occupied.size());
        } else if (v.order != Order::kUnsorted) {
          EXPECT_EQ(builds, occupied.size());
        } else {
          EXPECT_GE(builds, occupied.size());
        }
        if (v.stencil == Stencil::kFull) {
          // Iteration h is working particle h: an input row, or a slot of the sorted order.
          const auto map = detector.working_to_input();
          for (std::size_t h = 0; h < work.size(); ++h) {
            const std::size_t input = map.empty() ? h : map[h];
            ASSERT_EQ(work[h], run.tiled ? tiled.full_per_particle[input] : per_particle[input])
                << "iteration " << h;
          }
        }
      }
    }
  }
}

class CountingObserver : public DetectionObserver {
 public:
  void region_begin(int threads) override {
    ++region_begins;
    region_threads = threads;
  }
  void thread_begin(int thread) override {
    std::lock_guard<std::mutex> lock(mutex);
    begun.insert(thread);
  }
  void thread_end(int thread) override {
    std::lock_guard<std::mutex> lock(mutex);
    ended.insert(thread);
  }
  void region_end() override { ++region_ends; }

  int region_begins = 0, region_ends = 0, region_threads = 0;
  std::mutex mutex;
  std::set<int> begun, ended;
};

TEST(Detector, ObserverHooksRunOncePerRegionAndThread) {
  const Scene scene = uniform_scene(500, 0.1, 2);
  for (const int threads : {1, 3}) {
    CountingObserver observer;
    ContactDetector detector;
    DetectOptions options;
    options.diameter = 0.1;
    options.threads = threads;
    options.observer = &observer;
    detector.run(scene, options);
    EXPECT_EQ(observer.region_begins, 1);
    EXPECT_EQ(observer.region_ends, 1);
    EXPECT_EQ(observer.region_threads, threads);
    std::set<int> all;
    for (int t = 0; t < threads; ++t) all.insert(t);
    EXPECT_EQ(observer.begun, all);
    EXPECT_EQ(observer.ended, all);
  }
}

// Buffers are kept between runs: a big run followed by small ones (and by other variants and
// thread counts) must not leak stale rows, counts or offsets into the later results.
TEST(Detector, ReusedDetectorGivesFreshResults) {
  SceneSpec poly_spec;
  poly_spec.kind = SceneKind::kPolydisperse;
  poly_spec.n = 700;
  poly_spec.diameter = 0.12;
  poly_spec.seed = 4;
  struct Step {
    Scene scene;
    double d;
    Variant variant;
    int threads;
  };
  const std::vector<Step> steps = {
      {uniform_scene(3000, 0.07, 1), 0.07, parse_variant("cell/sorted/half/dynamic,7"), 3},
      {uniform_scene(40, 0.3, 2), 0.3, parse_variant("cell/sorted/half/dynamic,7"), 3},
      {uniform_scene(0, 0.3, 2), 0.3, parse_variant("particle/unsorted/full/static"), 2},
      {uniform_scene(2500, 0.08, 3), 0.08, parse_variant("particle/morton/full/guided,64"), 1},
      {generate_scene(poly_spec), 0.0, parse_variant("cell/unsorted/half/static,1"), 3},
      {uniform_scene(1, 0.3, 2), 0.3, parse_variant("particle/sorted/half/static"), 3},
      {uniform_scene(600, 0.2, 5), 0.2, parse_variant("cell/morton/full/dynamic,1"), 2},
      {uniform_scene(2000, 0.1, 6), 0.1, parse_variant("particle/sorted/half/guided,7/float"), 3},
      {uniform_scene(300, 0.1, 7), 0.1, parse_variant("cell/unsorted/full/static/float"), 1},
      {uniform_scene(300, 0.1, 7), 0.1, parse_variant("cell/unsorted/full/static"), 2},
  };
  ContactDetector detector;
  for (std::size_t k = 0; k < steps.size(); ++k) {
    const Step& step = steps[k];
    SCOPED_TRACE("step " + std::to_string(k) + ": " + to_string(step.variant) +
                 " N=" + std::to_string(step.scene.size()));
    DetectOptions options;
    options.variant = step.variant;
    options.diameter = step.d;
    options.threads = step.threads;
    const DetectRun run = detector.run(step.scene, options);
    const ContactList expected = brute_force_contacts(step.scene, step.d);
    EXPECT_TRUE(same_contacts(detector.canonical_contacts(), expected));
    EXPECT_EQ(run.contact_pairs, expected.pair_count());
  }
}

// The full stencil's first rows are written into the contact list's storage from the last run
// where thread 0 visits the first homes in row order; they must come out right when that
// storage is too small (the rows move to the buffer's own memory), fits them, or is shared
// with other threads' rows, and after half-stencil runs that use the storage differently.
TEST(Detector, RowsWrittenInPlaceMatchTheBruteForce) {
  struct Step {
    int n;
    double d;
    const char* variant;
    int threads;
  };
  const std::vector<Step> steps = {
      {500, 0.1, "particle/sorted/full/static", 1},     // nothing kept yet
      {3000, 0.1, "particle/sorted/full/static", 1},    // more rows than the storage holds
      {3000, 0.1, "particle/sorted/full/static", 1},    // in place
      {3000, 0.1, "particle/sorted/full/static", 3},    // thread 0 in place, the others copied
      {3000, 0.1, "cell/sorted/full/static", 2},        // the cell loop over sorted particles
      {3000, 0.1, "particle/unsorted/full/static", 2},  // input order
      {3000, 0.1, "cell/unsorted/full/static", 2},      // homes not in row order: copied
      {3000, 0.1, "particle/sorted/full/static,5", 2},  // chunks: copied
      {3000, 0.1, "particle/sorted/half/static", 2},
      {200, 0.1, "particle/sorted/full/dynamic,3", 1},  // fewer rows than last time
      {3000, 0.12, "particle/sorted/full/static/float", 1},
      // More rows than kept, at three threads: thread 0's block leaves the storage and is
      // copied with the others', every thread a slice.
      {6000, 0.1, "particle/sorted/full/static", 3},
      {6000, 0.1, "cell/sorted/full/static", 2},
  };
  ContactDetector detector;
  for (std::size_t k = 0; k < steps.size(); ++k) {
    const Step& step = steps[k];
    SCOPED_TRACE("step " + std::to_string(k) + ": " + step.variant +
                 " N=" + std::to_string(step.n) + " threads=" + std::to_string(step.threads));
    const Scene scene = uniform_scene(step.n, step.d, 11);
    DetectOptions options;
    options.variant = parse_variant(step.variant);
    options.diameter = step.d;
    options.threads = step.threads;
    detector.run(scene, options);
    const ContactList canonical = detector.canonical_contacts();
    EXPECT_TRUE(well_formed(canonical));
    EXPECT_TRUE(same_contacts(canonical, brute_force_contacts(scene, step.d)));
  }
}

// The SIMD test takes up to simd::kBlockHomes homes of one cell at once (each vector of
// candidates loaded once for all of them; the own cell's row skipped home by home). Every row
// must be the scalar loop's, entry for entry (the same partners in the same order): cells of one
// to dozens of particles, blocks cut by chunks and threads, both stencils and the float band.
// (The half stencil under static schedules only: elsewhere the reverse entries of a row come in
// the order the threads happened to take the chunks.)
TEST(Detector, BlocksOfHomesWriteTheScalarLoopsRows) {
  SceneSpec spec;
  spec.kind = SceneKind::kCore;
  spec.n = 3000;
  spec.diameter = 0.03;
  spec.seed = 5;
  const Scene scene = generate_scene(spec);
  auto rows = [&](const std::string& target, const char* variant, int threads) {
    select_simd_target(target);
    ContactDetector detector;
    DetectOptions options;
    options.variant = parse_variant(variant);
    options.diameter = spec.diameter;
    options.threads = threads;
    const DetectRun run = detector.run(scene, options);
    EXPECT_GE(run.max_cell_occupancy, 20u);
    return detector.contacts();
  };
  for (const std::string& target : simd_targets()) {
    if (target == "off") continue;
    for (const char* variant :
         {"particle/sorted/full/static", "particle/sorted/half/static,3",
          "cell/sorted/full/dynamic,2", "cell/morton/half/static",
          "particle/sorted/full/static/float", "particle/sorted/half/static,5/float"}) {
      for (const int threads : {1, 3}) {
        SCOPED_TRACE(target + " " + variant + " threads=" + std::to_string(threads));
        const ContactList scalar = rows("off", variant, threads);
        const ContactList blocks = rows(target, variant, threads);
        EXPECT_GT(scalar.pair_count(), 0u);
        EXPECT_TRUE(blocks.offsets == scalar.offsets);
        EXPECT_TRUE(blocks.partners == scalar.partners);
      }
    }
  }
  select_simd_target("best");
}

TEST(Detector, CopiedOutputShareFollowsWhereThreadZeroWritesInPlace) {
  auto share = [](const char* variant, int threads) {
    return copied_output_share(parse_variant(variant), threads);
  };
  EXPECT_EQ(share("particle/sorted/full/static", 1), 0.0);
  EXPECT_EQ(share("particle/sorted/full/dynamic,64", 1), 0.0);  // one thread visits in order
  EXPECT_EQ(share("particle/sorted/full/static", 2), 0.5);
  EXPECT_EQ(share("cell/sorted/full/static", 4), 0.75);
  EXPECT_EQ(share("particle/unsorted/full/static/float", 4), 0.75);
  EXPECT_EQ(share("particle/sorted/full/static,200", 2), 1.0);  // chunks: thread 0 not first
  EXPECT_EQ(share("particle/sorted/full/guided,8", 2), 1.0);
  EXPECT_EQ(share("cell/unsorted/full/static", 1), 1.0);    // homes not in row order
  EXPECT_EQ(share("particle/sorted/half/static", 1), 1.0);  // reverse entries between rows
  EXPECT_TRUE(writes_first_rows_in_place(parse_variant("cell/morton/full/static"), 2));
}

// The half stencil's threads pass reverse entries on where their homes are not runs of rows
// back to back (choose_row_blocks): chunks, dynamic or guided deals, unsorted particles.
TEST(Detector, ReverseEntriesArePassedOnWhereRowsAreNotTheHomes) {
  auto passes = [](const char* variant, int threads) {
    return passes_reverse_entries_on(parse_variant(variant), threads);
  };
  EXPECT_TRUE(passes("particle/sorted/half/static,200", 2));
  EXPECT_TRUE(passes("particle/sorted/half/dynamic,1024", 16));
  EXPECT_TRUE(passes("particle/sorted/half/guided,8", 4));
  EXPECT_TRUE(passes("particle/unsorted/half/static", 2));
  EXPECT_FALSE(passes("particle/sorted/half/static", 16));  // the block: rows are the homes
  EXPECT_FALSE(passes("cell/sorted/half/static", 16));
  EXPECT_FALSE(passes("particle/morton/half/balanced", 8));
  EXPECT_FALSE(passes("particle/sorted/half/static,200", 1));   // one thread passes nothing
  EXPECT_FALSE(passes("particle/sorted/full/static,200", 16));  // no reverse entries
}

}  // namespace
}  // namespace contactlab::test
