// The sink: particles below its level leave at rebuilds with their mass counted, stable ids
// stay valid (no longer dense), a checkpoint taken after removals restarts bit-identically,
// and a run that loses every particle goes on without them.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "contactlab/dem/checkpoint.hpp"
#include "contactlab/dem/discharge.hpp"
#include "contactlab/dem/engine.hpp"
#include "dem_support.hpp"

namespace contactlab::dem {
namespace {

double total_mass(const Particles& p) {
  double m = 0.0;
  for (double v : p.mass) m += v;
  return m;
}

// Every particle's state by stable id (ids sparse after removals): NaN where removed.
std::vector<double> state_by_sparse_id(const Engine& engine) {
  const Particles& p = engine.particles();
  std::vector<double> out(engine.id_capacity() * 9, std::nan(""));
  for (std::size_t a = 0; a < p.size(); ++a) {
    const double v[9] = {p.x[a],  p.y[a],  p.z[a],  p.vx[a], p.vy[a],
                         p.vz[a], p.wx[a], p.wy[a], p.wz[a]};
    std::memcpy(&out[std::size_t{9} * p.id[a]], v, sizeof v);
  }
  return out;
}

TEST(DemSink, RemovesParticlesBelowTheLevelAndCountsTheirMass) {
  auto [settings, particles] = test::draining_bed();
  const double mass0 = total_mass(particles);
  const std::size_t n0 = particles.size();
  Engine engine(settings, particles);
  engine.run_steps(4000);
  const Particles& p = engine.particles();
  ASSERT_GT(engine.removed_count(), 0u);
  ASSERT_GT(p.size(), 0u);
  EXPECT_EQ(p.size() + engine.removed_count(), n0);
  EXPECT_NEAR(total_mass(p) + engine.removed_mass(), mass0, 1e-12 * mass0);
  // Ids map to their particles; removed ids to kRemoved.
  EXPECT_EQ(engine.id_capacity(), n0);
  std::vector<bool> present(n0, false);
  for (std::size_t a = 0; a < p.size(); ++a) {
    EXPECT_EQ(engine.index_of(p.id[a]), a);
    present[p.id[a]] = true;
  }
  std::size_t removed = 0;
  for (std::uint32_t id = 0; id < n0; ++id) {
    if (!present[id]) {
      EXPECT_EQ(engine.index_of(id), Engine::kRemoved);
      ++removed;
    }
  }
  EXPECT_EQ(removed, engine.removed_count());
  // The discharge row counts the particles below the level not yet removed as discharged.
  const DischargeRow row = discharge_row(engine.snapshot());
  EXPECT_GE(row.discharged, engine.removed_count());
  EXPECT_EQ(row.discharged + row.left, n0);
  double below = 0.0;
  for (std::size_t a = 0; a < p.size(); ++a)
    below += p.z[a] < settings.sink_below_z ? p.mass[a] : 0;
  EXPECT_DOUBLE_EQ(row.discharged_kg, engine.removed_mass() + below);
}

TEST(DemSink, CheckpointAfterRemovalsRestartsBitIdentically) {
  auto [settings, particles] = test::draining_bed();
  settings.threads = 2;
  Engine whole(settings, particles);
  whole.run_steps(3000);
  const std::uint64_t removed_at_checkpoint = whole.removed_count();
  ASSERT_GT(removed_at_checkpoint, 0u);
  const std::string path = ::testing::TempDir() + "dem_sink_checkpoint.chk";
  write_checkpoint(whole, 3, path);
  whole.run_steps(2000);
  ASSERT_GT(whole.rebuilds(), 2u);

  settings.threads = 1;
  Engine restarted(settings, particles);
  EXPECT_EQ(read_checkpoint(restarted, path), 3);
  EXPECT_EQ(restarted.removed_count(), removed_at_checkpoint);
  EXPECT_EQ(restarted.particles().size(), particles.size() - removed_at_checkpoint);
  restarted.run_steps(2000);
  EXPECT_EQ(restarted.step_count(), whole.step_count());
  EXPECT_EQ(restarted.removed_count(), whole.removed_count());
  EXPECT_EQ(restarted.removed_mass(), whole.removed_mass());
  EXPECT_TRUE(test::bitwise_equal(state_by_sparse_id(restarted), state_by_sparse_id(whole)));
  EXPECT_EQ(restarted.energies().dissipated, whole.energies().dissipated);
}

// The removals are listed and the arrays compacted on the engine's threads: the run, its
// counters and its energy balance are the same for any thread count.
TEST(DemSink, RemovalsAreTheSameForAnyThreadCount) {
  auto [settings, particles] = test::draining_bed();
  settings.threads = 1;
  Engine reference(settings, particles);
  reference.run_steps(4000);
  ASSERT_GT(reference.removed_count(), 0u);
  for (const int threads : {2, 3}) {
    settings.threads = threads;
    Engine engine(settings, particles);
    engine.run_steps(4000);
    EXPECT_EQ(engine.removed_count(), reference.removed_count()) << threads;
    EXPECT_EQ(engine.removed_mass(), reference.removed_mass()) << threads;
    EXPECT_EQ(engine.energies().dissipated, reference.energies().dissipated) << threads;
    EXPECT_TRUE(test::bitwise_equal(state_by_sparse_id(engine), state_by_sparse_id(reference)))
        << threads;
  }
}

// Checkpoints written before the sink existed (format 1: no sink counters) are still read.
// A checkpoint of this build rewritten in an older format: format 3 lacks the time base (the
// time then restarts from the checkpoint's), format 2 also carries six arrays of synchronised
// velocities after wz (any values: they are dropped), format 1 lacks the sink's counters besides.
std::string older_checkpoint(std::string bytes, std::size_t n, char version) {
  // Magic (8), three counts (24), frames (4), time, step, rebuilds, overlaps, energy (40), the
  // sink's two counters (16), the time base (16); then each array is its length (8) and its
  // elements: id (4 bytes each), material and contacts (2), x, y, z, v and w (8).
  constexpr std::size_t kHeader = 92;
  bytes.erase(kHeader, 16);
  bytes[7] = version;
  if (version == '3') return bytes;
  const std::size_t after_w = kHeader + (8 + 4 * n) + 2 * (8 + 2 * n) + 9 * (8 + 8 * n);
  std::string array(8 + 8 * n, '\0');
  const std::uint64_t length = n;
  std::memcpy(array.data(), &length, 8);
  for (int k = 0; k < 6; ++k) bytes.insert(after_w, array);
  if (version == '1') bytes.erase(76, 16);
  return bytes;
}

class DemSinkOlderCheckpoint : public ::testing::TestWithParam<char> {};

TEST_P(DemSinkOlderCheckpoint, IsStillRead) {
  auto [settings, particles] = test::small_bed();
  Engine original(settings, particles);
  original.run_steps(300);
  // A file of its own per format: ctest runs the three at once.
  const std::string format(1, GetParam());
  const std::string now = ::testing::TempDir() + "dem_sink_now" + format + ".chk";
  const std::string old = ::testing::TempDir() + "dem_sink_old" + format + ".chk";
  write_checkpoint(original, 1, now);
  std::ifstream in(now, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::ofstream(old, std::ios::binary)
      << older_checkpoint(bytes, original.particles().size(), GetParam());
  Engine restored(settings, particles);
  EXPECT_EQ(read_checkpoint(restored, old), 1);
  EXPECT_EQ(restored.step_count(), original.step_count());
  EXPECT_EQ(restored.removed_count(), 0u);
  original.run_steps(200);
  restored.run_steps(200);
  EXPECT_TRUE(test::bitwise_equal(state_by_sparse_id(restored), state_by_sparse_id(original)));
}

INSTANTIATE_TEST_SUITE_P(Formats, DemSinkOlderCheckpoint, ::testing::Values('1', '2', '3'),
                         [](const auto& format) { return std::string("Format") + format.param; });

TEST(DemSink, ARunWithoutParticlesGoesOn) {
  auto [settings, particles] = test::draining_bed();
  settings.sink_below_z = 1.0;  // above everything: all leave at the first rebuild after start
  Engine engine(settings, particles);
  while (engine.particles().size() > 0 && engine.step_count() < 5000) engine.step();
  ASSERT_EQ(engine.particles().size(), 0u);
  EXPECT_EQ(engine.removed_count(), particles.size());
  engine.run_steps(10);
  EXPECT_EQ(engine.pairs().size(), 0u);
  EXPECT_EQ(discharge_row(engine.snapshot()).left, 0u);
}

}  // namespace
}  // namespace contactlab::dem
