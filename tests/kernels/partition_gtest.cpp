// The decomposition of partition.hpp (no MPI): every particle owned by exactly one rank, ranks
// own stretches of the curve, the work split balanced within one particle's work (dense cells
// shared by ranks), empty ranks when ranks outnumber particles, halos counted as the
// particles next door; and the block-cyclic home blocks of detector.hpp.
#include <gtest/gtest.h>

#include <set>
#include <tuple>

#include "contactlab/kernels/error.hpp"
#include "contactlab/kernels/partition.hpp"
#include "test_support.hpp"

namespace contactlab::test {
namespace {

CellHistogram clustered_histogram(std::size_t n, double d, std::uint64_t seed) {
  SceneSpec spec;
  spec.kind = SceneKind::kClustered;
  spec.n = n;
  spec.diameter = d;
  spec.seed = seed;
  const Scene scene = generate_scene(spec);
  const CellGrid grid(scene.box, d, CellNumbering::kLinear);
  CellHistogram histogram;
  add_to_histogram(grid, scene, histogram);
  return histogram;
}

TEST(Partition, EveryParticleHasOneOwnerAndTotalsAreKept) {
  const CellHistogram histogram = clustered_histogram(20000, 0.02, 7);
  for (const int ranks : {1, 2, 3, 7, 64}) {
    for (const auto method : {PartitionMethod::kWork, PartitionMethod::kVolume}) {
      const Partition partition(histogram, ranks, method);
      Partition indexed = partition;
      indexed.index_cells();
      ASSERT_EQ(partition.ranks(), ranks);
      std::uint64_t particles = 0, work = 0;
      const auto& dims = histogram.dims;
      for (int z = 0; z < dims[2]; ++z) {
        for (int y = 0; y < dims[1]; ++y) {
          for (int x = 0; x < dims[0]; ++x) {
            const std::uint32_t count = histogram.count[histogram.key(x, y, z)];
            const auto [first, last] = partition.owners(x, y, z);
            ASSERT_EQ(indexed.owners(x, y, z), std::make_pair(first, last));
            if (count == 0) {
              EXPECT_EQ(first, -1);
              continue;
            }
            ASSERT_GE(first, 0);
            ASSERT_LE(first, last);
            ASSERT_LT(last, ranks);
            for (std::uint32_t k = 0; k < count; ++k) {
              const int owner = partition.owner(x, y, z, k);
              ASSERT_GE(owner, first);
              ASSERT_LE(owner, last);
            }
            particles += count;
            work += cell_work(histogram, x, y, z);
          }
        }
      }
      const PartitionReport report = evaluate_partition(histogram, partition);
      std::uint64_t reported_particles = 0;
      for (const auto& load : report.ranks) reported_particles += load.particles;
      EXPECT_EQ(reported_particles, particles);
      EXPECT_EQ(report.total_work, work);
      EXPECT_EQ(particles, 20000u);
    }
  }
}

// The owner is non-decreasing along the curve (cells by Morton key, then particles by input
// row): each rank's particles are one stretch.
TEST(Partition, RanksOwnContiguousStretchesOfTheCurve) {
  const CellHistogram histogram = clustered_histogram(5000, 0.05, 3);
  for (const int ranks : {5, 64}) {
    const Partition partition(histogram, ranks, PartitionMethod::kWork);
    std::vector<std::tuple<std::uint64_t, std::uint32_t, int>> owners;
    const auto& dims = histogram.dims;
    for (int z = 0; z < dims[2]; ++z)
      for (int y = 0; y < dims[1]; ++y)
        for (int x = 0; x < dims[0]; ++x)
          for (std::uint32_t k = 0; k < histogram.count[histogram.key(x, y, z)]; ++k)
            owners.emplace_back(morton_key(x, y, z), k, partition.owner(x, y, z, k));
    std::sort(owners.begin(), owners.end());
    for (std::size_t k = 1; k < owners.size(); ++k)
      EXPECT_LE(std::get<2>(owners[k - 1]), std::get<2>(owners[k]));
  }
}

// The stated bound: each rank's work is the mean within one particle's work (the split cuts
// between particles), so max / mean - 1 <= max particle work / mean work; on a clustered scene
// whose densest cell holds more than a rank's share, within 5% up to 256 ranks.
TEST(Partition, WorkSplitIsBalancedWithinOneParticlesWork) {
  const CellHistogram histogram = clustered_histogram(100000, 0.01, 11);
  for (const int ranks : {2, 4, 16, 64, 256}) {
    const PartitionReport report =
        evaluate_partition(histogram, Partition(histogram, ranks, PartitionMethod::kWork));
    const double mean = double(report.total_work) / ranks;
    EXPECT_LE(report.work_imbalance, double(report.max_particle_work) / mean + 1e-9)
        << ranks << " ranks";
    EXPECT_LT(report.work_imbalance, 0.05) << ranks << " ranks";
    if (ranks >= 64) {
      EXPECT_GT(double(report.max_cell_work), mean) << "the scene no longer has a dense cell";
    }
  }
}

TEST(Partition, SyntheticUniformWorkSplitsEvenly) {
  CellHistogram histogram;
  histogram.dims = {16, 16, 16};
  histogram.count.assign(std::size_t{16} * 16 * 16, 4);
  for (const int ranks : {2, 4, 8, 64}) {
    const PartitionReport volume =
        evaluate_partition(histogram, Partition(histogram, ranks, PartitionMethod::kVolume));
    EXPECT_LT(volume.particle_imbalance, 1e-12) << ranks;
    const PartitionReport work =
        evaluate_partition(histogram, Partition(histogram, ranks, PartitionMethod::kWork));
    const double mean = double(work.total_work) / ranks;
    EXPECT_LE(work.work_imbalance, double(work.max_particle_work) / mean + 1e-9) << ranks;
  }
}

TEST(Partition, MoreRanksThanParticlesLeavesEmptyRanks) {
  CellHistogram histogram;
  histogram.dims = {2, 1, 1};
  histogram.count = {1, 2};
  const Partition partition(histogram, 6, PartitionMethod::kWork);
  const PartitionReport report = evaluate_partition(histogram, partition);
  int empty = 0, busy = 0;
  for (const auto& load : report.ranks) (load.particles == 0 ? empty : busy)++;
  EXPECT_EQ(busy, 3);
  EXPECT_EQ(empty, 3);
  // Each particle's rank holds the two others as ghosts, from the two other ranks.
  for (const auto& load : report.ranks) {
    EXPECT_EQ(load.halo_particles, load.particles ? 2u : 0u);
    EXPECT_EQ(load.halo_sources, load.particles ? 2u : 0u);
  }
}

// A row of six cells in three stretches of two: the middle rank receives ghosts from both ends
// (two messages), the ends from the middle only.
TEST(Partition, HaloSourcesAreTheRanksNextDoor) {
  CellHistogram histogram;
  histogram.dims = {6, 1, 1};
  histogram.count = {1, 1, 1, 1, 1, 1};
  const Partition partition(histogram, 3, PartitionMethod::kVolume);
  const PartitionReport report = evaluate_partition(histogram, partition);
  ASSERT_EQ(report.ranks.size(), 3u);
  EXPECT_EQ(report.ranks[0].halo_sources, 1u);
  EXPECT_EQ(report.ranks[1].halo_sources, 2u);
  EXPECT_EQ(report.ranks[2].halo_sources, 1u);
  EXPECT_EQ(report.ranks[1].halo_particles, 2u);
}

// A dense cell with more work than a rank's share is shared by several ranks.
TEST(Partition, ADenseCellIsSharedBetweenRanks) {
  CellHistogram histogram;
  histogram.dims = {4, 1, 1};
  histogram.count = {1, 100, 1, 1};
  const Partition partition(histogram, 4, PartitionMethod::kWork);
  const auto [first, last] = partition.owners(1, 0, 0);
  EXPECT_LT(first, last);
  EXPECT_EQ(partition.shared_cells(), std::vector<std::uint64_t>{histogram.key(1, 0, 0)});
  const PartitionReport report = evaluate_partition(histogram, partition);
  EXPECT_LE(report.work_imbalance,
            double(report.max_particle_work) * 4 / double(report.total_work) + 1e-9);
}

TEST(Partition, RejectsNoRanksAndUnknownMethods) {
  CellHistogram histogram;
  histogram.count = {1};
  EXPECT_THROW(Partition(histogram, 0, PartitionMethod::kWork), InputError);
  EXPECT_THROW(parse_partition_method("rcb"), InputError);
  EXPECT_EQ(parse_partition_method("volume"), PartitionMethod::kVolume);
}

TEST(HomeBlocks, DealEveryIterationToExactlyOneProcess) {
  for (const std::uint64_t total : {0u, 1u, 199u, 200u, 1001u, 4000u}) {
    for (const std::uint32_t count : {1u, 2u, 3u, 7u}) {
      std::vector<int> seen(total, 0);
      std::uint64_t sum = 0;
      for (std::uint32_t index = 0; index < count; ++index) {
        const HomeBlocks blocks{200, count, index};
        const std::uint64_t size = blocks.size(total);
        sum += size;
        for (std::uint64_t k = 0; k < size; ++k) {
          const std::uint64_t i = blocks.at(k);
          ASSERT_LT(i, total);
          ASSERT_EQ((i / 200) % count, index);
          ++seen[i];
        }
      }
      EXPECT_EQ(sum, total);
      for (const int s : seen) EXPECT_EQ(s, 1);
    }
  }
}

// Block-cyclic homes split the detection: the union of the processes' contacts is the whole.
TEST(HomeBlocks, ProcessesTogetherFindEveryContact) {
  SceneSpec spec;
  spec.kind = SceneKind::kClustered;
  spec.n = 3000;
  spec.diameter = 0.04;
  spec.seed = 5;
  const Scene scene = generate_scene(spec);
  for (const Variant& variant : covering_variants()) {
    if (variant.precision != Precision::kDouble) continue;
    const Detected all = detect(scene, variant, spec.diameter, 2);
    std::set<std::pair<std::uint32_t, std::uint32_t>> pairs;
    std::uint64_t found = 0;
    for (std::uint32_t index = 0; index < 3; ++index) {
      ContactDetector detector;
      DetectOptions options;
      options.variant = variant;
      options.diameter = spec.diameter;
      options.threads = 2;
      options.blocks = {64, 3, index};
      const DetectRun run = detector.run(scene, options);
      const ContactList list = detector.canonical_contacts();
      // The work the schedule model sees is this process's iterations, in its loop's order.
      const LoopWork work = detector.iteration_work(scene, options);
      DetectOptions whole = options;
      whole.blocks = {};
      const LoopWork every = detector.iteration_work(scene, whole);
      ASSERT_EQ(work.tests.size(), options.blocks.size(every.tests.size())) << to_string(variant);
      std::uint64_t tests = 0;
      for (std::uint64_t k = 0; k < work.tests.size(); ++k) {
        ASSERT_EQ(work.tests[k], every.tests[options.blocks.at(k)]) << to_string(variant);
        tests += work.tests[k];
      }
      EXPECT_EQ(tests, run.candidate_tests) << to_string(variant);
      for (std::size_t i = 0; i < list.particle_count(); ++i) {
        for (const std::uint32_t j : list.partners_of(i)) {
          if (j <= i) continue;
          pairs.emplace(static_cast<std::uint32_t>(i), j);
          ++found;
        }
      }
    }
    EXPECT_EQ(found, all.contacts.pair_count()) << to_string(variant) << ": found more than once";
    EXPECT_EQ(pairs.size(), all.contacts.pair_count()) << to_string(variant);
  }
}

}  // namespace
}  // namespace contactlab::test
