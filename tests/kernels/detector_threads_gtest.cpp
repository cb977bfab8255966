// Detection at the thread counts users run, 1 to 16 (oversubscribed on small machines), against
// the brute force: the half stencil's rows (reverse entries passed between threads, rows split by
// the homes' runs or by weight), the registration's radix sort (its top digit widens with the
// thread count) and the buffers a detection keeps, which must not grow with the thread count.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include "test_support.hpp"

namespace contactlab::test {
namespace {

const std::vector<int> kThreads = {1, 2, 3, 4, 8, 16};

struct Case {
  std::string name;
  Scene scene;
  double diameter;
  ContactList expected;
};

// A centre-clustered scene (the paper's kind: dense cells in the middle, sparse ones around),
// the dense core, and a polydisperse one; a few thousand particles each.
const std::vector<Case>& cases() {
  static const std::vector<Case> all = [] {
    std::vector<Case> made;
    auto add = [&](std::string name, SceneKind kind, std::uint64_t n, double diameter,
                   std::uint64_t seed) {
      SceneSpec spec;
      spec.kind = kind;
      spec.n = n;
      spec.diameter = diameter;
      spec.seed = seed;
      spec.size_ratio = 4.0;  // polydisperse only
      Scene scene = generate_scene(spec);
      ContactList expected = brute_force_contacts(scene, diameter);
      made.push_back({std::move(name), std::move(scene), diameter, std::move(expected)});
    };
    add("clustered", SceneKind::kClustered, 4000, 0.025, 7);
    add("core", SceneKind::kCore, 3000, 0.02, 8);
    add("polydisperse", SceneKind::kPolydisperse, 2500, 0.08, 9);
    return made;
  }();
  return all;
}

std::vector<Variant> variants_under_test() {
  std::vector<Variant> variants;
  const std::vector<Schedule> schedules = {{ScheduleKind::kStatic, 0},
                                           {ScheduleKind::kStatic, 5},
                                           {ScheduleKind::kDynamic, 3},
                                           {ScheduleKind::kGuided, 2},
                                           {ScheduleKind::kBalanced, 0}};
  for (const auto loop : {LoopKind::kParticle, LoopKind::kCell}) {
    for (const auto order : {Order::kUnsorted, Order::kSorted}) {
      for (const auto stencil : {Stencil::kHalf, Stencil::kFull}) {
        for (const Schedule& schedule : schedules) {
          Variant v{loop, order, stencil, schedule, Precision::kDouble};
          variants.push_back(v);
          if (schedule.kind == ScheduleKind::kDynamic) {
            v.grid = GridIndex::kHashed;
            variants.push_back(v);
          }
        }
      }
    }
  }
  return variants;
}

TEST(DetectionThreads, EveryThreadCountMatchesTheBruteForce) {
  const std::vector<Variant> variants = variants_under_test();
  for (const Case& c : cases()) {
    for (const Variant& variant : variants) {
      for (const int threads : kThreads) {
        SCOPED_TRACE(c.name + " " + to_string(variant) + " threads=" + std::to_string(threads));
        const Detected d = detect(c.scene, variant, c.diameter, threads);
        ASSERT_TRUE(same_contacts(d.contacts, c.expected));
        EXPECT_EQ(d.run.threads, threads);
      }
    }
  }
}

// Scenes past copy_for_random_reads are read at random from copies (the sorted orders' staged
// records, the unsorted double loops' copy in huge pages), smaller ones from their arrays, which
// the brute-force cases above check. Too large for the brute force here, each variant is held
// against the float unsorted loop, which reads neither copy.
TEST(DetectionThreads, LargeScenesReadCopiesAndFindTheSameContacts) {
  for (const auto kind : {SceneKind::kClustered, SceneKind::kPolydisperse}) {
    SceneSpec spec;
    spec.kind = kind;
    spec.n = 180000;
    spec.diameter = kind == SceneKind::kClustered ? 0.004 : 0.02;  // 2.5 and 2 contacts a particle
    spec.seed = 12;
    const Scene scene = generate_scene(spec);
    ASSERT_TRUE(copy_for_random_reads(scene));
    const ContactList reference =
        detect(scene, parse_variant("particle/unsorted/full/static/float"), spec.diameter, 2)
            .contacts;
    ASSERT_GT(reference.partners.size(), spec.n / 2);
    for (const char* text : {"particle/unsorted/full/static", "cell/unsorted/full/static",
                             "particle/sorted/full/static", "particle/sorted/half/static,64",
                             "cell/morton/half/static"}) {
      for (const int threads : {1, 3}) {
        SCOPED_TRACE(std::string(text) + " at " + std::to_string(threads) + " threads");
        EXPECT_TRUE(detect(scene, parse_variant(text), spec.diameter, threads).contacts ==
                    reference);
      }
    }
  }
}

// The balanced schedule's point: on a centre-clustered scene the block schedule's threads get
// very unequal shares of the work, the balanced blocks nearly equal ones. The work is what the
// blocks weigh, a thread's pair tests plus kHomeTests for each of its homes (counted, not
// timed: the same on any machine). The worst thread's work over the mean, at 16 threads.
TEST(DetectionThreads, BalancedBlocksShareTheWorkOfAClusteredScene) {
  SceneSpec spec;
  spec.kind = SceneKind::kClustered;
  spec.n = 100000;
  spec.diameter = 0.01;
  spec.seed = 3;
  const Scene scene = generate_scene(spec);
  auto worst_over_mean = [&](const Variant& variant) {
    const Detected d = detect(scene, variant, spec.diameter, 16);
    std::uint64_t worst = 0, sum = 0, tests = 0, homes = 0;
    for (std::size_t t = 0; t < d.run.thread_tests.size(); ++t) {
      const std::uint64_t work = d.run.thread_tests[t] + kHomeTests * d.run.thread_homes[t];
      worst = std::max(worst, work);
      sum += work;
      tests += d.run.thread_tests[t];
      homes += d.run.thread_homes[t];
    }
    EXPECT_EQ(tests, d.run.candidate_tests);
    EXPECT_EQ(homes, spec.n);  // every particle a home of one thread
    return static_cast<double>(worst) * 16.0 / static_cast<double>(sum);
  };
  for (const auto stencil : {Stencil::kFull, Stencil::kHalf}) {
    for (const auto loop : {LoopKind::kParticle, LoopKind::kCell}) {
      const Variant block{loop, Order::kSorted, stencil, {ScheduleKind::kStatic, 0}};
      const Variant balanced{loop, Order::kSorted, stencil, {ScheduleKind::kBalanced, 0}};
      SCOPED_TRACE(to_string(balanced));
      const double block_worst = worst_over_mean(block);
      const double balanced_worst = worst_over_mean(balanced);
      std::printf("%s: worst thread's work / mean, block %.3f, balanced %.3f\n",
                  to_string(balanced).c_str(), block_worst, balanced_worst);
      EXPECT_GT(block_worst, 1.5);
      // A cell is the cell loop's unit: the centre's cells of hundreds are coarse grains.
      EXPECT_LT(balanced_worst, loop == LoopKind::kParticle ? 1.1 : 1.4);
    }
  }
}

// The detector reports the balanced schedule's weighing (what the emulation replays): some time
// at two threads, none at one (the block runs) nor under another schedule.
TEST(DetectionThreads, TheBalancedWeighingIsReportedWhereItRuns) {
  const Case& c = cases().front();
  const Variant balanced{
      LoopKind::kParticle, Order::kSorted, Stencil::kFull, {ScheduleKind::kBalanced, 0}};
  const Variant block{
      LoopKind::kParticle, Order::kSorted, Stencil::kFull, {ScheduleKind::kStatic, 0}};
  EXPECT_GT(detect(c.scene, balanced, c.diameter, 2).run.weigh_s, 0.0);
  EXPECT_EQ(detect(c.scene, balanced, c.diameter, 1).run.weigh_s, 0.0);
  EXPECT_EQ(detect(c.scene, block, c.diameter, 2).run.weigh_s, 0.0);
}

// Ghosts (a home range) and a block-cyclic share of the loop (replicated MPI): the rows at any
// thread count are those of one thread.
TEST(DetectionThreads, HomeRangesAndBlocksAreTheSameAtEveryThreadCount) {
  const Case& c = cases().front();
  const auto n = static_cast<std::uint32_t>(c.scene.size());
  struct Homes {
    HomeRange range;
    HomeBlocks blocks;
  };
  const std::vector<Homes> homes = {{{0, n - n / 4}, {}}, {{n / 5, n}, {}}, {{}, {7, 3, 1}}};
  for (const Homes& h : homes) {
    for (const auto stencil : {Stencil::kHalf, Stencil::kFull}) {
      for (const Schedule schedule :
           {Schedule{ScheduleKind::kStatic, 0}, Schedule{ScheduleKind::kDynamic, 4}}) {
        const Variant variant{LoopKind::kParticle, Order::kSorted, stencil, schedule,
                              Precision::kDouble};
        ContactList one;
        for (const int threads : kThreads) {
          SCOPED_TRACE(to_string(variant) + " homes [" + std::to_string(h.range.first) + ", " +
                       std::to_string(h.range.last) + ") block " + std::to_string(h.blocks.block) +
                       " threads=" + std::to_string(threads));
          ContactDetector detector;
          DetectOptions options;
          options.variant = variant;
          options.diameter = c.diameter;
          options.threads = threads;
          options.homes = h.range;
          options.blocks = h.blocks;
          detector.run(c.scene, options);
          const ContactList got = detector.canonical_contacts();
          if (threads == 1) {
            one = got;
            ASSERT_GT(one.partners.size(), 0u);
          } else {
            ASSERT_TRUE(same_contacts(got, one));
          }
        }
      }
    }
  }
}

// The registration (radix sort by cell key, cell index, reordering) is the same for any thread
// count, on a grid whose keys take three digits, so that the top digit goes first and widens
// (8 bits up to 4 threads, 10 at 16, 12 at 64).
TEST(DetectionThreads, RegistrationIsTheSameAtEveryThreadCount) {
  const Case& c = cases().front();
  for (const bool hashed : {false, true}) {
    const CellGrid grid(c.scene.box, 0.004, CellNumbering::kLinear);  // 250^3 cells: 24-bit keys
    CellRegistry one;
    SortedCoordinates one_sorted;
    one.assign(grid, c.scene, &one_sorted, 1, hashed);
    for (const int threads : {2, 3, 4, 8, 16, 64}) {
      SCOPED_TRACE("threads=" + std::to_string(threads) + (hashed ? " hashed" : " dense"));
      CellRegistry many;
      SortedCoordinates sorted;
      many.assign(grid, c.scene, &sorted, threads, hashed);
      EXPECT_TRUE(many.slot_particle == one.slot_particle);
      EXPECT_TRUE(many.cell_begin == one.cell_begin);
      EXPECT_TRUE(many.occupied.key == one.occupied.key);
      EXPECT_TRUE(many.occupied.begin == one.occupied.begin);
      EXPECT_TRUE(sorted.x == one_sorted.x && sorted.y == one_sorted.y && sorted.z == one_sorted.z);
      EXPECT_EQ(many.max_occupancy, one.max_occupancy);
      EXPECT_EQ(many.occupancy_squares, one.occupancy_squares);
    }
  }
}

// What a detection keeps between runs, at 1 to 64 threads: the same bytes but for vectors of a
// few entries per thread (the sort's digit counts the largest: at most 4096 a thread), plus the
// half stencil's reverse entries passed between threads, at most 16 bytes a contact pair at any
// thread count. (Counts per (thread, particle) had made it N x P.)
TEST(DetectionThreads, BuffersDoNotGrowWithTheThreadCount) {
  SceneSpec spec;
  spec.kind = SceneKind::kClustered;
  spec.n = 40000;
  spec.diameter = 0.01;
  spec.seed = 3;
  const Scene scene = generate_scene(spec);
  constexpr std::size_t kPerThreadBytes = 64 << 10;
  for (const std::string name : {"particle/sorted/half/static", "particle/sorted/half/dynamic,64",
                                 "cell/unsorted/half/static", "particle/sorted/full/static,200"}) {
    const Variant variant = parse_variant(name);
    ContactDetector::BufferBytes one;
    std::uint64_t pairs = 0;
    for (const int threads : {1, 2, 4, 16, 64}) {
      SCOPED_TRACE(name + " threads=" + std::to_string(threads));
      ContactDetector detector;
      DetectOptions options;
      options.variant = variant;
      options.diameter = spec.diameter;
      options.threads = threads;
      const DetectRun run = detector.run(scene, options);
      const ContactDetector::BufferBytes bytes = detector.buffer_bytes();
      if (threads == 1) {
        one = bytes;
        pairs = run.contact_pairs;
        EXPECT_EQ(bytes.spill_bytes, 0u);
        continue;
      }
      EXPECT_EQ(run.contact_pairs, pairs);
      EXPECT_LE(bytes.spill_bytes, 16 * pairs);
      EXPECT_LE(bytes.total - bytes.spill_bytes, one.total + threads * kPerThreadBytes);
    }
  }
}

}  // namespace
}  // namespace contactlab::test
