// The DEM neighbour list against an O(N^2) brute force with periodic images, the radix sort,
// and the history merge across a rebuild that reorders particles.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <numeric>
#include <set>
#include <tuple>

#include "contactlab/dem/pair_list.hpp"
#include "dem_support.hpp"

namespace contactlab::dem {
namespace {

using Key = std::tuple<std::uint32_t, std::uint32_t>;

std::set<Key> brute_force(const Particles& p, const Domain& d, double skin) {
  std::set<Key> pairs;
  for (std::size_t a = 0; a < p.size(); ++a) {
    for (std::size_t b = a + 1; b < p.size(); ++b) {
      double dist_sq = 0;
      const double da[3] = {p.x[a] - p.x[b], p.y[a] - p.y[b], p.z[a] - p.z[b]};
      for (int k = 0; k < 3; ++k) {
        double v = da[k];
        if (d.periodic[k]) v -= d.length(k) * std::round(v / d.length(k));
        dist_sq += v * v;
      }
      const double reach = p.radius[a] + p.radius[b] + skin;
      if (dist_sq < reach * reach)
        pairs.insert({std::min(p.id[a], p.id[b]), std::max(p.id[a], p.id[b])});
    }
  }
  return pairs;
}

TEST(DemNeighborList, EqualsBruteForceWithPeriodicImages) {
  auto [settings, particles] = test::small_bed(200);
  Xoshiro256 rng(9);
  for (std::size_t k = 0; k < particles.size(); ++k) {  // scatter, some across the faces
    particles.x[k] = 0.01 * rng.uniform();
    particles.y[k] = 0.01 * rng.uniform();
    particles.z[k] = 0.02 * rng.uniform();
  }
  const double skin = 2e-4;
  const std::set<Key> expected = brute_force(particles, settings.domain, skin);
  NeighborBuilder builder;
  PairList pairs;
  builder.rebuild(particles, pairs, settings.domain, skin);
  std::set<Key> got;
  for (std::size_t k = 0; k < pairs.size(); ++k) {
    const std::uint32_t a = particles.id[pairs.i[k]], b = particles.id[pairs.j[k]];
    EXPECT_TRUE(got.insert({std::min(a, b), std::max(a, b)}).second) << "pair listed twice";
  }
  EXPECT_EQ(got, expected);
  // Reordered by cell: z (the slowest cell axis) is non-decreasing in cell-sized steps.
  std::size_t descents = 0;
  for (std::size_t k = 1; k < particles.size(); ++k)
    descents += particles.z[k] + 3e-3 < particles.z[k - 1];
  EXPECT_EQ(descents, 0u);
  // Rows hold each particle's pairs as i; the j lists (indexed on demand) hold the others: every
  // pair once each.
  EXPECT_FALSE(pairs.j_sides_indexed);
  RadixBuffers buffers;
  pairs.index_j_sides(particles.size(), 2, buffers);
  std::vector<int> seen_i(pairs.size(), 0), seen_j(pairs.size(), 0);
  for (std::size_t a = 0; a < particles.size(); ++a) {
    for (std::uint32_t k = pairs.rows[a]; k < pairs.rows[a + 1]; ++k) {
      EXPECT_EQ(pairs.i[k], a);
      ++seen_i[k];
    }
    for (std::uint32_t e = pairs.j_offsets[a]; e < pairs.j_offsets[a + 1]; ++e) {
      EXPECT_EQ(pairs.j[pairs.j_pairs[e]], a);
      ++seen_j[pairs.j_pairs[e]];
    }
  }
  EXPECT_EQ(std::count(seen_i.begin(), seen_i.end(), 1), static_cast<long>(pairs.size()));
  EXPECT_EQ(std::count(seen_j.begin(), seen_j.end(), 1), static_cast<long>(pairs.size()));
}

TEST(DemNeighborList, RadixSortSortsStably) {
  std::vector<std::uint64_t> keys{5, 3, 5, 1, 1u << 20, 3};
  std::vector<std::uint32_t> payload{0, 1, 2, 3, 4, 5};
  std::vector<std::uint64_t> ks;
  std::vector<std::uint32_t> ps;
  radix_sort(keys, payload, 21, ks, ps);
  EXPECT_EQ(keys, (std::vector<std::uint64_t>{1, 3, 3, 5, 5, 1u << 20}));
  EXPECT_EQ(payload, (std::vector<std::uint32_t>{3, 1, 5, 0, 2, 4}));
}

// On threads, each counting and scattering its own range (300,000 keys: up to 9 threads take
// part), the order is the stable sort's, ties included.
TEST(DemNeighborList, RadixSortOnThreadsIsTheStableSort) {
  constexpr std::size_t kN = 300000;
  std::vector<std::uint64_t> start(kN);
  std::uint64_t state = 12345;
  for (auto& key : start) {
    state = state * 6364136223846793005u + 1442695040888963407u;
    key = (state >> 20) & ((std::uint64_t{1} << 26) - 1) & ~std::uint64_t{0xff};  // many ties
  }
  std::vector<std::uint32_t> expected(kN);
  std::iota(expected.begin(), expected.end(), 0u);
  std::stable_sort(expected.begin(), expected.end(),
                   [&](std::uint32_t a, std::uint32_t b) { return start[a] < start[b]; });
  for (const int threads : {1, 2, 3, 9, 16}) {
    std::vector<std::uint64_t> keys = start, ks;
    std::vector<std::uint32_t> payload(kN), ps;
    std::iota(payload.begin(), payload.end(), 0u);
    radix_sort(keys, payload, 26, ks, ps, threads);
    EXPECT_EQ(payload, expected) << threads << " threads";
    EXPECT_TRUE(std::is_sorted(keys.begin(), keys.end())) << threads << " threads";
  }
}

TEST(DemNeighborList, HistoryFollowsItsPairThroughAReorder) {
  auto [settings, particles] = test::small_bed(100);
  const double skin = 5e-4;
  NeighborBuilder builder;
  PairList pairs;
  builder.rebuild(particles, pairs, settings.domain, skin);
  ASSERT_GT(pairs.size(), 10u);
  // A spring per pair that encodes its ids: seen from the lower id it is (lo - hi, lo, hi)
  // x 1e-9; seen from i it is that times sign (+1 when id_i < id_j).
  auto spring = [](double a, double b) {
    const double sign = a < b ? 1.0 : -1.0;
    return std::array<double, 3>{sign * (std::min(a, b) - std::max(a, b)) * 1e-9,
                                 sign * std::min(a, b) * 1e-9, sign * std::max(a, b) * 1e-9};
  };
  for (std::size_t k = 0; k < pairs.size(); ++k) {
    const auto h = spring(particles.id[pairs.i[k]], particles.id[pairs.j[k]]);
    pairs.hx[k] = h[0];
    pairs.hy[k] = h[1];
    pairs.hz[k] = h[2];
  }
  const std::size_t before = pairs.size();
  // Move everything so the cell order changes (a shift by half a period and a mirror in x).
  for (std::size_t k = 0; k < particles.size(); ++k) {
    particles.x[k] = 0.01 - particles.x[k] + 1e-9;
    particles.y[k] += 0.005;
  }
  const RebuildStats stats = builder.rebuild(particles, pairs, settings.domain, skin);
  EXPECT_EQ(pairs.size(), before);
  EXPECT_EQ(stats.carried_contacts, before);
  for (std::size_t k = 0; k < pairs.size(); ++k) {
    const double a = particles.id[pairs.i[k]], b = particles.id[pairs.j[k]];
    const auto h = spring(a, b);
    EXPECT_EQ(pairs.hx[k], h[0]);
    EXPECT_EQ(pairs.hy[k], h[1]);
    EXPECT_EQ(pairs.hz[k], h[2]);
  }
}

// The engine's rebuilds look each new pair's spring up in the old list's rows; a list without
// rows for the particles goes through the merge by stable-id keys (as the sink's springs do). Both
// carry the same springs, bit for bit (signs where a pair turned round, a -0 component, pairs
// that stopped touching), on a scene whose order changes and whose pairs cross periodic faces.
TEST(DemNeighborList, OldRowsCarryWhatTheKeyedMergeCarries) {
  auto [settings, particles] = test::small_bed(200);
  Xoshiro256 rng(5);
  for (std::size_t k = 0; k < particles.size(); ++k) {
    particles.x[k] = 0.01 * rng.uniform();
    particles.y[k] = 0.01 * rng.uniform();
    particles.z[k] = 0.02 * rng.uniform();
  }
  const double skin = 2e-4;
  NeighborBuilder builder;
  PairList pairs;
  builder.rebuild(particles, pairs, settings.domain, skin);
  ASSERT_GT(pairs.size(), 20u);
  for (std::size_t k = 0; k < pairs.size(); ++k) {
    const double v = rng.uniform() - 0.5;
    const std::array<double, 3> h = k % 4 == 0   ? std::array<double, 3>{0.0, 0.0, 0.0}
                                    : k % 4 == 1 ? std::array<double, 3>{-0.0, v, 0.0}
                                                 : std::array<double, 3>{v, -v, 2 * v};
    pairs.hx[k] = h[0];
    pairs.hy[k] = h[1];
    pairs.hz[k] = h[2];
  }
  for (std::size_t k = 0; k < particles.size(); ++k) {  // mirrored, and moved a little
    particles.x[k] = 0.01 - particles.x[k] + 1e-9 + 2e-5 * (rng.uniform() - 0.5);
    particles.z[k] += 2e-5 * (rng.uniform() - 0.5);
  }
  Particles keyed_particles = particles;
  PairList keyed = pairs;
  keyed.rows.clear();  // no rows for these particles: the keyed merge
  NeighborBuilder keyed_builder;
  const RebuildStats by_rows = builder.rebuild(particles, pairs, settings.domain, skin);
  const RebuildStats by_keys = keyed_builder.rebuild(keyed_particles, keyed, settings.domain, skin);
  EXPECT_GT(by_rows.carried_contacts, pairs.size() / 4);
  EXPECT_EQ(by_rows.carried_contacts, by_keys.carried_contacts);
  ASSERT_EQ(particles.id, keyed_particles.id);
  ASSERT_EQ(pairs.size(), keyed.size());
  auto bits = [](double v) { return std::bit_cast<std::uint64_t>(v); };
  for (std::size_t k = 0; k < pairs.size(); ++k) {
    EXPECT_EQ(pairs.i[k], keyed.i[k]);
    EXPECT_EQ(pairs.j[k], keyed.j[k]);
    EXPECT_EQ(pairs.image[k], keyed.image[k]);
    EXPECT_EQ(bits(pairs.hx[k]), bits(keyed.hx[k])) << k;
    EXPECT_EQ(bits(pairs.hy[k]), bits(keyed.hy[k])) << k;
    EXPECT_EQ(bits(pairs.hz[k]), bits(keyed.hz[k])) << k;
  }
}

}  // namespace
}  // namespace contactlab::dem
