// The near pairs (near_pairs.hpp) against a brute-force filter of the neighbour list: who is
// taken (periodic images included, across 64-pair words, for any thread count), their fields
// and rows, springs carried from choice to choice, and springs written back.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "contactlab/dem/near_pairs.hpp"
#include "contactlab/dem/pair_list.hpp"
#include "contactlab/kernels/rng.hpp"

namespace contactlab::dem {
namespace {

constexpr std::size_t kStride = 12;  // the force pass's kinematics blocks: x y z r vx vy vz ...
constexpr double kNoneHot = std::numeric_limits<double>::infinity();

// Particles on the x axis, 1 mm apart give or take 0.1 mm, radii 0.46 - 0.54 mm: pairs
// (a, a - 1) (gaps of -0.28 to 0.28 mm) and (a, a - 2) (about 1 mm), j < i, grouped by i, and
// the last particle with the first across the periodic side. Springs, m* and 1/k_t tell the
// pairs apart.
struct Line {
  std::vector<double> kin;
  PairList all;
  std::size_t particles = 0;
  double length = 0.0;  // m: the periodic x side
};

Line make_line(std::size_t n, std::uint64_t seed) {
  Line line;
  line.particles = n;
  line.length = 1e-3 * static_cast<double>(n);
  line.kin.assign(kStride * n, 0.0);
  Xoshiro256 rng(seed);
  for (std::size_t a = 0; a < n; ++a) {
    line.kin[kStride * a + 0] = 1e-3 * static_cast<double>(a) + 2e-4 * (rng.uniform() - 0.5);
    line.kin[kStride * a + 1] = 1e-5 * rng.uniform();
    line.kin[kStride * a + 3] = 4.6e-4 + 0.8e-4 * rng.uniform();
  }
  PairList& q = line.all;
  q.shift[kNoImage] = {0, 0, 0};
  q.shift[14] = {line.length, 0, 0};  // code (1 + 1) + 3 + 9: the partner one side length on
  auto add = [&](std::uint32_t i, std::uint32_t j, std::uint8_t image) {
    q.i.push_back(i);
    q.j.push_back(j);
    q.image.push_back(image);
    const double k = static_cast<double>(q.i.size());
    q.hx.push_back(k);
    q.hy.push_back(-k);
    q.hz.push_back(0.5 * k);
    q.m_star.push_back(1e-3 * k);
    q.inv_kt.push_back(2e-3 * k);
  };
  for (std::uint32_t a = 1; a < n; ++a) {
    if (a + 1 == n) add(a, 0, 14);  // x_a - (x_0 + L): the first particle's image beyond a
    add(a, a - 1, kNoImage);
    if (a >= 2) add(a, a - 2, kNoImage);
  }
  q.index_rows(n, 1);
  return line;
}

double gap(const Line& line, std::size_t k) {
  const PairList& q = line.all;
  const double* ki = &line.kin[kStride * q.i[k]];
  const double* kj = &line.kin[kStride * q.j[k]];
  const auto& sh = q.shift[q.image[k]];
  return std::hypot(ki[0] - kj[0] - sh[0], ki[1] - kj[1] - sh[1], ki[2] - kj[2] - sh[2]) - ki[3] -
         kj[3];
}

TEST(NearPairs, TakesThePairsWithinTheMarginInTheListsOrder) {
  const Line line = make_line(300, 11);
  const double margin = 1e-4;
  std::vector<std::size_t> expected;
  for (std::size_t k = 0; k < line.all.size(); ++k) {
    if (gap(line, k) < margin) expected.push_back(k);
  }
  ASSERT_GT(line.all.size(), 3 * 64u) << "more than a few words of pairs";
  ASSERT_GT(expected.size(), 100u);
  ASSERT_LT(expected.size(), line.all.size() - 100) << "some pairs left out";
  PairList all = line.all;
  for (const int threads : {1, 3, 8}) {
    NearPairs near;
    near.build(all, true, line.kin.data(), kStride, line.particles, margin, kNoneHot, threads);
    const PairList& q = near.list;
    ASSERT_EQ(q.size(), expected.size()) << threads << " threads";
    for (std::size_t n = 0; n < q.size(); ++n) {
      const std::size_t k = expected[n];
      EXPECT_EQ(q.i[n], all.i[k]);
      EXPECT_EQ(q.j[n], all.j[k]);
      EXPECT_EQ(q.image[n], all.image[k]);
      EXPECT_EQ(q.hx[n], all.hx[k]);
      EXPECT_EQ(q.hz[n], all.hz[k]);
      EXPECT_EQ(q.m_star[n], all.m_star[k]);
      EXPECT_EQ(q.inv_kt[n], all.inv_kt[k]);
    }
    // Rows: particle a's near pairs are [rows[a], rows[a + 1]).
    ASSERT_EQ(q.rows.size(), line.particles + 1);
    for (std::size_t a = 0; a < line.particles; ++a) {
      for (std::size_t n = q.rows[a]; n < q.rows[a + 1]; ++n) EXPECT_EQ(q.i[n], a);
    }
    EXPECT_EQ(q.rows.back(), q.size());
    EXPECT_EQ(q.shift[14][0], line.length);
    EXPECT_EQ(near.builds, 1u);
    EXPECT_EQ(near.margin, margin);
    EXPECT_FALSE(near.stale());
  }
}

// The periodic pair (the last particle with the first's image) is tested with its shift: put
// them 0.9 mm apart through the side and it is taken, though the two lie 49 mm apart.
TEST(NearPairs, PeriodicPairsAreTestedThroughTheirImage) {
  Line line = make_line(50, 3);
  line.kin[kStride * 49] = line.length - 0.45e-3;
  line.kin[kStride * 0] = 0.45e-3;
  line.kin[kStride * 49 + 3] = line.kin[kStride * 0 + 3] = 0.45e-3;
  NearPairs near;
  near.build(line.all, true, line.kin.data(), kStride, line.particles, 1e-5, kNoneHot, 1);
  bool found = false;
  for (std::size_t n = 0; n < near.list.size(); ++n) {
    found = found || (near.list.i[n] == 49 && near.list.j[n] == 0 && near.list.image[n] == 14);
  }
  EXPECT_TRUE(found);
}

// A second choice over the same neighbour list takes the springs of the first (which the force
// pass has moved on), gives a pair that comes near a zero spring (it was apart), and write_back
// puts every spring in its place with zeros for the pairs left out.
TEST(NearPairs, SpringsGoFromChoiceToChoiceAndBackToTheList) {
  Line line = make_line(200, 5);
  PairList& all = line.all;
  const double margin = 1e-4;
  NearPairs near;
  near.build(all, true, line.kin.data(), kStride, line.particles, margin, kNoneHot, 2);
  std::vector<bool> was_near(all.size(), false);
  for (std::size_t k = 0; k < all.size(); ++k) was_near[k] = gap(line, k) < margin;
  // The force pass's new springs: 1000 + the old.
  for (double& h : near.list.hx) h += 1000.0;
  // Particles move: every fourth one by 0.3 mm along x.
  for (std::size_t a = 0; a < line.particles; a += 4) line.kin[kStride * a] += 3e-4;
  near.build(all, false, line.kin.data(), kStride, line.particles, margin, kNoneHot, 3);
  std::size_t n = 0, kept = 0, entered = 0;
  for (std::size_t k = 0; k < all.size(); ++k) {
    if (!(gap(line, k) < margin)) continue;
    ASSERT_LT(n, near.list.size());
    ASSERT_EQ(near.list.i[n], all.i[k]);
    ASSERT_EQ(near.list.j[n], all.j[k]);
    if (was_near[k]) {
      EXPECT_EQ(near.list.hx[n], all.hx[k] + 1000.0) << "pair " << k;
      EXPECT_EQ(near.list.hy[n], all.hy[k]);
      ++kept;
    } else {
      EXPECT_EQ(near.list.hx[n], 0.0) << "pair " << k << " was apart";
      EXPECT_EQ(near.list.hz[n], 0.0);
      ++entered;
    }
    ++n;
  }
  EXPECT_EQ(n, near.list.size());
  EXPECT_GT(kept, 10u);
  EXPECT_GT(entered, 3u);
  for (double& h : near.list.hz) h = -7.0;
  near.write_back(all, 3);
  n = 0;
  for (std::size_t k = 0; k < all.size(); ++k) {
    if (gap(line, k) < margin) {
      EXPECT_EQ(all.hx[k], near.list.hx[n]);
      EXPECT_EQ(all.hz[k], -7.0);
      ++n;
    } else {
      EXPECT_EQ(all.hx[k], 0.0) << "pair " << k << " left out";
      EXPECT_EQ(all.hy[k], 0.0);
      EXPECT_EQ(all.hz[k], 0.0);
    }
  }
}

// A hot particle (faster than the speed given) has every pair taken, however far; its bit is
// set, the others' not, with a zero byte past the last particle's.
TEST(NearPairs, EveryPairOfAHotParticleIsTaken) {
  Line line = make_line(77, 9);
  for (const std::size_t a : {5u, 40u, 76u}) line.kin[kStride * a + 5] = 0.2;  // vy [m/s]
  line.kin[kStride * 41 + 4] = 0.09;                                           // not hot at 0.1 m/s
  NearPairs near;
  near.build(line.all, true, line.kin.data(), kStride, line.particles, 1e-5, 0.1, 2);
  ASSERT_EQ(near.hot.size(), 77u / 8 + 2);
  EXPECT_EQ(near.hot.back(), 0u);
  EXPECT_EQ(near.hot_count, 3u);
  for (std::size_t a = 0; a < line.particles; ++a) {
    const bool hot = a == 5 || a == 40 || a == 76;
    EXPECT_EQ((near.hot[a / 8] >> (a % 8)) & 1, hot ? 1 : 0) << a;
  }
  std::size_t n = 0;
  for (std::size_t k = 0; k < line.all.size(); ++k) {
    const std::uint32_t i = line.all.i[k], j = line.all.j[k];
    const bool hot = i == 5 || i == 40 || i == 76 || j == 5 || j == 40 || j == 76;
    if (!(hot || gap(line, k) < 1e-5)) continue;
    ASSERT_LT(n, near.list.size());
    EXPECT_EQ(near.list.i[n], i);
    EXPECT_EQ(near.list.j[n], j);
    ++n;
  }
  EXPECT_EQ(n, near.list.size());
}

TEST(NearPairs, StaleOnceTwiceTheMovesReachTheMargin) {
  NearPairs near;
  near.margin = 1e-5;
  near.moved = 0.49e-5;
  EXPECT_FALSE(near.stale());
  near.moved = 0.5e-5;
  EXPECT_TRUE(near.stale());
}

}  // namespace
}  // namespace contactlab::dem
