// The DEM step's emulation with a memory system (step_emulation.hpp): the bytes a step moves
// by hand from the work counts and the layout, and the roofline it adds: where the bandwidth a
// thread count draws cannot move the bytes in the replayed time, the phase takes the bytes'
// time; where it can, nothing changes. (Nothing here asserts a timing.)
#include <gtest/gtest.h>

#include <memory>

#include "contactlab/tuner_dem/step_emulation.hpp"
#include "dem_support.hpp"

namespace contactlab::dem {
namespace {

TEST(DemStepTraffic, BytesFromTheWorkCountsAndTheLayout) {
  const StepTraffic t = step_traffic(1000, 4000);
  // Per pair 73 bytes (i, j, image, m*, 1/k_t, the spring read and written); per particle 520
  // in the batched force pass and drift (each array once: read, and written back if written;
  // force, torque, |F| and the contact count stay in the sums).
  EXPECT_DOUBLE_EQ(t.bytes, 73.0 * 4000 + 520.0 * 1000);
  EXPECT_EQ(t.footprint_bytes, 440u * 1000 + 73u * 4000);
}

TEST(DemStepEmulation, TheRooflineBindsOnlyWhereTheBytesTakeLonger) {
  auto [settings, particles] = test::small_bed();
  settings.threads = 1;
  Engine engine(settings, particles);
  engine.run_steps(5);
  const ForceLoopWork work = force_loop_work(engine.pairs(), engine.particles().size());
  const ForceVariant variant = settings.force_variant;
  ForceCosts costs;
  for (double& c : costs.per_pair) c = 1e-8;
  costs.per_particle_update = 2e-8;
  PhaseTimes phases;
  phases.pair_forces_s = 1e-3;
  phases.integrate_s = 2e-4;
  phases.neighbor_s = 1e-5;
  const MeasuredStep one{1, phases, phases.total_s()};
  const std::vector<int> threads{1, 2, 16};
  const std::vector<EmulatedStep> plain = emulate_steps(work, variant, costs, one, one, threads);

  // A memory system that barely grows past one thread (1 GB/s, 1.05 at two, towards 1.1), and
  // a step whose bytes take 0.9 of its one-thread force pass and drift: compute binds at one
  // thread, the bytes at sixteen, where the replay falls further than the bandwidth rises.
  const double compute_1 = plain[0].force_s + plain[0].integrate_s;
  const double compute_16 = plain[2].force_s + plain[2].integrate_s;
  ASSERT_LT(compute_16, 0.8 * compute_1);
  const tuner::BandwidthCurve curve({{1, 1e9}, {2, 1.05e9}}, 1.1e9);
  StepTraffic traffic;
  traffic.bytes = 0.9 * compute_1 * 1e9;
  const std::vector<EmulatedStep> priced =
      emulate_steps(work, variant, costs, one, one, threads, curve, traffic);
  ASSERT_EQ(priced.size(), 3u);
  EXPECT_DOUBLE_EQ(priced[0].force_s, plain[0].force_s) << "compute binds at one thread";
  EXPECT_DOUBLE_EQ(priced[0].integrate_s, plain[0].integrate_s);
  EXPECT_DOUBLE_EQ(priced[0].bytes_per_s, 1e9);
  EXPECT_DOUBLE_EQ(priced[0].memory_s, traffic.bytes / 1e9);
  const double bw16 = curve.at(16);
  EXPECT_DOUBLE_EQ(priced[2].bytes_per_s, bw16);
  EXPECT_NEAR(priced[2].force_s + priced[2].integrate_s, traffic.bytes / bw16, 1e-15);
  EXPECT_GT(priced[2].force_s, plain[2].force_s) << "the bytes bind at sixteen threads";
  // Both parts grow in proportion; the neighbour list is not priced by bytes.
  EXPECT_NEAR(priced[2].force_s / priced[2].integrate_s, plain[2].force_s / plain[2].integrate_s,
              1e-12);
  EXPECT_DOUBLE_EQ(priced[2].neighbor_s, plain[2].neighbor_s);
  EXPECT_DOUBLE_EQ(plain[2].bytes_per_s, 0.0) << "no curve: no bandwidth";
}

}  // namespace
}  // namespace contactlab::dem
