// The decomposed DEM step's emulation: one rank is the measured one-process cost; strong
// scaling on a column of particles gains about R until the halo and the messages weigh; a slow
// network lowers the speed-up; weak scaling keeps the step within the exchange of one rank.
#include <gtest/gtest.h>

#include "contactlab/tuner_dem/mpi_emulation.hpp"

namespace contactlab::dem {
namespace {

// A column of 4,000 touching spheres (d = 1 mm) in a 10 x 10 x 160 mm box: slabs along z.
std::pair<EngineSettings, Particles> column() {
  EngineSettings s;
  s.domain.lo = {0, 0, 0};
  s.domain.hi = {0.01, 0.01, 0.16};
  s.skin = 1e-4;
  Particles p;
  std::uint32_t id = 0;
  for (int z = 0; z < 160; ++z) {
    for (int y = 0; y < 5; ++y) {
      for (int x = 0; x < 5; ++x) {
        p.add(id++, 0, 0.001 + 0.002 * x, 0.001 + 0.002 * y, 0.0005 + 0.001 * z, 5e-4, 2500.0);
      }
    }
  }
  return {s, p};
}

PairList list_of(Particles& p, const EngineSettings& s) {
  PairList pairs;
  NeighborBuilder builder;
  builder.rebuild(p, pairs, s.domain, s.skin, 1);
  return pairs;
}

TEST(DemMpiEmulation, OneRankIsTheMeasuredCostAndStrongScalingSaturates) {
  auto [settings, particles] = column();
  const PairList pairs = list_of(particles, settings);
  const double c = 1e-7;  // s per unit of work: 1.6 ms a step at one rank
  const NetworkModel network;
  const auto points =
      emulate_dem_mpi_strong(particles, pairs, settings, {1, 2, 4, 16, 64}, 2, c, network);
  ASSERT_EQ(points.size(), 5u);
  double total = 0.0;
  for (const double w : particle_work(particles, pairs)) total += w;
  EXPECT_DOUBLE_EQ(points[0].step_s, c * total);
  EXPECT_DOUBLE_EQ(points[0].speedup, 1.0);
  EXPECT_EQ(points[0].ghosts_max, 0u);
  EXPECT_GT(points[1].speedup, 1.8);
  EXPECT_LT(points[1].speedup, 2.0);
  for (std::size_t k = 1; k < points.size(); ++k) {
    EXPECT_GT(points[k].speedup, points[k - 1].speedup) << points[k].ranks << " ranks";
    EXPECT_LT(points[k].speedup, points[k].ranks) << points[k].ranks << " ranks";
  }
  // 64 ranks: 2.5 layers each, and a halo of 1.1 mm (2 layers on each side): the ghosts
  // outweigh the rank's own particles.
  EXPECT_LT(points[4].speedup, 32.0);
  EXPECT_EQ(points[4].neighbours_max, 2);
  NetworkModel slow;
  slow.latency_s = 1e-3;
  const auto slow_points = emulate_dem_mpi_strong(particles, pairs, settings, {16}, 2, c, slow);
  EXPECT_LT(slow_points[0].speedup, points[3].speedup);
}

TEST(DemMpiEmulation, WeakScalingStaysWithinTheHaloAndTheMessages) {
  auto [settings, particles] = column();
  const PairList pairs = list_of(particles, settings);
  const double c = 1e-7;
  const NetworkModel network;
  const auto points = emulate_dem_mpi_weak(particles, pairs, settings, {1, 2, 1024}, 2, c, network);
  ASSERT_EQ(points.size(), 3u);
  EXPECT_DOUBLE_EQ(points[0].speedup, 1.0);
  EXPECT_EQ(points[1].neighbours_max, 1);
  EXPECT_EQ(points[2].neighbours_max, 2);
  // 1,024 ranks: each holds 2 layers of ghosts at each end besides its 160, and waits in a
  // 10-step reduction: efficiency about 0.95.
  EXPECT_GT(points[2].speedup, 0.9);
  EXPECT_LT(points[2].speedup, 1.0);
  EXPECT_GT(points[2].reduction_s, points[1].reduction_s);
}

}  // namespace
}  // namespace contactlab::dem
