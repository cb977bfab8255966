// The force model: the pair list's work per block adds up to the list, predictions follow the
// cost terms by hand on a one-thread run, the schedules' foreign j sides are counted, the
// calibration fits every term with the stated number of runs, and the re-tuner switches only
// past its margin. (Nothing here asserts a timing.)
#include <gtest/gtest.h>

#include <memory>
#include <numeric>

#include "contactlab/tuner_dem/force_model.hpp"
#include "dem_support.hpp"

namespace contactlab::dem {
namespace {

// A free block of touching spheres on a cubic lattice (pitch 2 mm, radii 0.9-1 mm),
// shaken: every particle has neighbours, pairs reach into earlier blocks of rows.
std::unique_ptr<Engine> bed_engine(const ForceVariant& variant, int threads, std::uint32_t n) {
  auto [settings, unused] = test::small_bed();
  settings.walls.clear();
  settings.gravity = {0, 0, 0};
  const std::uint32_t side = 10, layers = (n + side * side - 1) / (side * side);
  const double pitch = 2e-3;
  settings.domain.lo = {0, 0, 0};
  settings.domain.hi = {side * pitch, side * pitch, layers * pitch};
  settings.domain.periodic = {false, false, false};  // no wrap: pairs reach only back
  Particles p;
  Xoshiro256 rng(7);
  for (std::uint32_t k = 0; k < side * side * layers; ++k) {
    // NOLINTNEXTLINE(bugprone-integer-division): the lattice layer, an integer on purpose
    const double z = (k / (side * side) + 0.5) * pitch;
    p.add(k, 0, (k % side + 0.5) * pitch, (k / side % side + 0.5) * pitch, z,
          9e-4 + 1e-4 * rng.uniform(), 2500.0);
    p.vx[k] = 0.2 * (2 * rng.uniform() - 1);
    p.vy[k] = 0.2 * (2 * rng.uniform() - 1);
    p.vz[k] = 0.2 * (2 * rng.uniform() - 1);
  }
  settings.force_variant = variant;
  settings.threads = threads;
  auto engine = std::make_unique<Engine>(settings, p);
  engine->run_steps(20);
  return engine;
}

std::uint64_t sum(const std::vector<std::uint32_t>& v) {
  return std::accumulate(v.begin(), v.end(), std::uint64_t{0});
}

TEST(DemForceModel, WorkPerBlockAddsUpToThePairList) {
  const auto engine = bed_engine(ForceVariant{}, 1, 600);
  const PairList& q = engine->pairs();
  const ForceLoopWork w = force_loop_work(q, engine->particles().size());
  EXPECT_EQ(w.block_particles.size(), (engine->particles().size() + 63) / 64);
  EXPECT_EQ(sum(w.block_particles), engine->particles().size());
  EXPECT_EQ(sum(w.own_pairs), q.size());
  EXPECT_EQ(w.total_pairs(), q.size());
  EXPECT_EQ(sum(w.j_side_pairs), q.size());
  // Pairs whose j lies in an earlier block, counted per (block, earlier block).
  std::uint64_t across = 0;
  for (std::size_t k = 0; k < q.size(); ++k) across += q.j[k] / 64 != q.i[k] / 64;
  EXPECT_EQ(sum(w.reach_pairs), across);
  EXPECT_GT(across, 0u);
  ASSERT_EQ(w.reach_offsets.size(), w.block_particles.size() + 1);
  for (std::size_t b = 0; b < w.block_particles.size(); ++b) {
    for (std::uint32_t e = w.reach_offsets[b]; e < w.reach_offsets[b + 1]; ++e) {
      EXPECT_LT(w.reach_block[e], b);
    }
  }
}

// On one thread every term is its unit count times its cost.
TEST(DemForceModel, OneThreadPredictionIsTheSumOfItsTerms) {
  const auto engine = bed_engine(ForceVariant{}, 1, 600);
  const ForceLoopWork w = force_loop_work(engine->pairs(), engine->particles().size());
  const double pairs = static_cast<double>(w.total_pairs());
  const double n = static_cast<double>(w.particles);
  const double blocks = static_cast<double>(w.block_particles.size());
  ForceCosts c;
  c.per_pair[0] = 1.0;   // ordered
  c.per_pair[1] = 2.0;   // per-thread
  c.per_pair[2] = 5.0;   // atomic
  c.per_pair[3] = 0.75;  // full list, per side
  c.per_particle_update = 3.0;
  c.per_particle_fused = 4.0;
  c.per_particle_serial_walls = 1.0;
  c.per_particle_arrays = 0.5;
  c.per_grab = 10.0;
  auto predict = [&](const char* text) {
    return predict_force_pass(w, parse_force_variant(text), 1, c).seconds;
  };
  EXPECT_DOUBLE_EQ(predict("ordered/static"), pairs + 3.0 * n);
  EXPECT_DOUBLE_EQ(predict("ordered/static/update=fused"), pairs + 4.0 * n);
  EXPECT_DOUBLE_EQ(predict("ordered/static/walls=serial"), pairs + 1.0 * n + 2.0 * n);
  EXPECT_DOUBLE_EQ(predict("per-thread/static"), 2.0 * pairs + 0.5 * n + 3.0 * n);
  EXPECT_DOUBLE_EQ(predict("atomic/static"), 5.0 * pairs + 3.0 * n);
  EXPECT_DOUBLE_EQ(predict("full-list/static"), 0.75 * 2.0 * pairs + 3.0 * n);
  // dynamic,1: one grab per block and one final empty grab, in the pass and in the update.
  EXPECT_DOUBLE_EQ(predict("full-list/dynamic,1"),
                   0.75 * 2.0 * pairs + 3.0 * n + 2.0 * 10.0 * (blocks + 1.0));
}

// At two threads, static,1 sends alternate blocks to each thread: most pairs that reach into an
// earlier block reach into the other thread's; the static block split only at its boundary.
TEST(DemForceModel, ForeignJSidesFollowTheSchedule) {
  const auto engine = bed_engine(ForceVariant{}, 1, 6000);
  const ForceLoopWork w = force_loop_work(engine->pairs(), engine->particles().size());
  ForceCosts c;
  c.per_foreign_j_side[1] = 1.0;  // per-thread: only this term
  const double block_split =
      predict_force_pass(w, parse_force_variant("per-thread/static"), 2, c).seconds;
  const double alternate =
      predict_force_pass(w, parse_force_variant("per-thread/static,1"), 2, c).seconds;
  EXPECT_GT(alternate, 4.0 * block_split);
  EXPECT_LE(alternate, static_cast<double>(sum(w.reach_pairs)));
}

TEST(DemForceModel, CalibrationFitsEveryTermWithTheStatedRuns) {
  const EngineFactory make = [](const ForceVariant& v, int threads) {
    return bed_engine(v, threads, 1500);
  };
  const ForceCosts one = calibrate_force_costs(make, 1, 5);
  EXPECT_EQ(one.calibration_runs, 9);  // seven structures, the ordered pass twice more
  const ForceCosts two = calibrate_force_costs(make, 2, 5);
  EXPECT_EQ(two.calibration_runs, 12);
  for (const ForceCosts* c : {&one, &two}) {
    for (int a = 0; a < 4; ++a) {
      EXPECT_GT(c->per_pair[a], 0.0) << a;
      EXPECT_GE(c->per_foreign_j_side[a], 0.0) << a;
    }
    EXPECT_GT(c->per_particle_update, 0.0);
    EXPECT_GE(c->calibration_spread, 0.0);
    EXPECT_GE(c->per_grab, 0.0);
    EXPECT_GE(c->per_particle_arrays, 0.0);
  }
}

TEST(DemForceModel, RetunerSwitchesOnlyPastItsMargin) {
  const auto engine = bed_engine(ForceVariant{}, 2, 600);
  ForceCosts c;
  c.per_pair[0] = 1.0;
  c.per_pair[1] = 1.0;
  c.per_pair[2] = 1.0;
  c.per_pair[3] = 0.1;  // the full list's two sides cost a fifth of an ordered pair
  c.per_particle_update = 1.0;
  const std::vector<ForceVariant> candidates{ForceVariant{},
                                             parse_force_variant("full-list/static")};
  const ForceRetuner eager(c, candidates, 0.05);
  const ForceRetuner::Decision d = eager.decide(*engine, ForceVariant{});
  EXPECT_TRUE(d.switched);
  EXPECT_EQ(d.variant, parse_force_variant("full-list/static"));
  EXPECT_GT(d.predicted_gain, 0.05);
  const ForceRetuner reluctant(c, candidates, 10.0);
  const ForceRetuner::Decision kept = reluctant.decide(*engine, ForceVariant{});
  EXPECT_FALSE(kept.switched);
  EXPECT_EQ(kept.variant, ForceVariant{});
  EXPECT_EQ(kept.best, parse_force_variant("full-list/static")) << "the best is named when kept";
}

TEST(DemForceModel, RetunerKeepsTheVariantWhenTheCalibrationsSpreadExceedsTheGain) {
  const auto engine = bed_engine(ForceVariant{}, 2, 600);
  ForceCosts c;
  c.per_pair[0] = 1.0;
  c.per_pair[1] = 1.0;
  c.per_pair[2] = 1.0;
  c.per_pair[3] = 0.45;  // two sides at 0.45: the full list a little cheaper, a gain of some %
  c.per_particle_update = 1.0;
  const std::vector<ForceVariant> candidates{ForceVariant{},
                                             parse_force_variant("full-list/static")};
  const double gain =
      ForceRetuner(c, candidates, 0.0).decide(*engine, ForceVariant{}).predicted_gain;
  ASSERT_GT(gain, 0.0);
  // The calibration's runs spread by more than the predicted gain: the current variant stays,
  // whatever the stated margin; with a spread below it, the stated margin rules.
  c.calibration_spread = 2.0 * gain;
  const ForceRetuner noisy(c, candidates, 0.0);
  EXPECT_DOUBLE_EQ(noisy.margin(), 2.0 * gain);
  const ForceRetuner::Decision kept = noisy.decide(*engine, ForceVariant{});
  EXPECT_FALSE(kept.switched);
  EXPECT_EQ(kept.variant, ForceVariant{});
  c.calibration_spread = 0.5 * gain;
  const ForceRetuner quiet(c, candidates, 0.0);
  EXPECT_DOUBLE_EQ(quiet.margin(), 0.5 * gain);
  EXPECT_TRUE(quiet.decide(*engine, ForceVariant{}).switched);
  EXPECT_DOUBLE_EQ(ForceRetuner(c, candidates, 0.9).margin(), 0.9) << "a larger stated margin";
}

}  // namespace
}  // namespace contactlab::dem
