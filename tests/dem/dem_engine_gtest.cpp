// The engine's guarantees: bit-identical trajectories for any thread count, contact history
// carried across rebuilds and reorders, the synchronised velocity removing the dashpot's
// half-step bias, energy bookkeeping.
#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <cstring>
#include <numbers>
#include <string>
#include <vector>

#include "contactlab/dem/contact_law.hpp"
#include "contactlab/dem/engine.hpp"
#include "contactlab/dem/validation.hpp"
#include "contactlab/kernels/error.hpp"
#include "dem_support.hpp"

namespace contactlab::dem {
namespace {

// Whether a force variant's bits are fixed at a thread count (force_variant.hpp): always, but
// for the atomic adds and the per-thread arrays dealt out dynamically on more than one thread,
// whose order of additions follows the threads' timing.
bool bits_fixed(const std::string& text, int threads) {
  const ForceVariant v = parse_force_variant(text);
  return threads == 1 || thread_count_invariant(v) ||
         (v.accumulation == Accumulation::kPerThread && v.schedule.kind == ScheduleKind::kStatic);
}

// Two runs' forces, torques, |F|, contact counts and the pair list's springs, bit for bit.
void expect_same_forces_and_springs(const Engine& a, const Engine& b, const std::string& what) {
  const Particles &p = a.particles(), &q = b.particles();
  for (auto member : {&Particles::fx, &Particles::fy, &Particles::fz, &Particles::tx,
                      &Particles::ty, &Particles::tz, &Particles::force_magnitude}) {
    EXPECT_TRUE(test::bitwise_equal(p.*member, q.*member)) << what;
  }
  EXPECT_EQ(p.contacts, q.contacts) << what;
  for (auto spring : {&PairList::hx, &PairList::hy, &PairList::hz}) {
    EXPECT_TRUE(test::bitwise_equal(a.pairs().*spring, b.pairs().*spring)) << what;
  }
}

// Eight threads on the 150 particles: ranges of about 16 particles, shorter than a j side's
// reach, moved step by step by the threads' timings (RowRanges) and, oversubscribed, far apart.
TEST(DemEngine, BitIdenticalForAnyThreadCount) {
  auto [settings, particles] = test::small_bed();
  std::vector<double> reference;
  for (const int threads : {1, 2, 3, 8}) {
    EngineSettings s = settings;
    s.threads = threads;
    Engine engine(s, particles);
    engine.run_steps(1500);
    EXPECT_GT(engine.rebuilds(), 1u);
    const std::vector<double> state = test::state_by_id(engine);
    if (reference.empty()) {
      reference = state;
    } else {
      EXPECT_TRUE(test::bitwise_equal(reference, state)) << threads << " threads";
    }
  }
}

// The fused pass (each particle gathered as soon as its rows are done) and the split one (pair
// loop, then gather) give the same bits, at any thread count.
TEST(DemEngine, FusedAndSplitForcePassesAgree) {
  auto [settings, particles] = test::small_bed();
  std::vector<double> reference;
  for (const bool fused : {true, false}) {
    for (const int threads : {1, 3}) {
      EngineSettings s = settings;
      s.force_variant.fused_update = fused;
      s.threads = threads;
      Engine engine(s, particles);
      engine.run_steps(800);
      const std::vector<double> state = test::state_by_id(engine);
      if (reference.empty()) {
        reference = state;
      } else {
        EXPECT_TRUE(test::bitwise_equal(reference, state)) << fused << " " << threads;
      }
    }
  }
}

// run_steps(k) drifts each next step in the finish's pass over the particles: the same bits
// as k calls of step() (springs, forces, rebuilds included), for every accumulation, schedule,
// update placement and thread count whose bits are fixed (bits_fixed).
TEST(DemEngine, BatchedStepsMatchSingleSteps) {
  auto [settings, particles] = test::small_bed();
  for (const char* variant : {"ordered/static", "ordered/static/update=fused", "per-thread/static",
                              "per-thread/dynamic,2", "atomic/static", "full-list/guided,1",
                              "full-list/static/update=fused", "ordered/static/walls=serial"}) {
    for (const int threads : {1, 3}) {
      if (!bits_fixed(variant, threads)) continue;
      EngineSettings s = settings;
      s.force_variant = parse_force_variant(variant);
      s.threads = threads;
      Engine batched(s, particles), single(s, particles);
      batched.run_steps(700);
      for (int k = 0; k < 700; ++k) single.step();
      EXPECT_GT(batched.rebuilds(), 1u);
      EXPECT_EQ(batched.rebuilds(), single.rebuilds()) << variant;
      EXPECT_EQ(batched.particle_steps(), single.particle_steps()) << variant;
      EXPECT_TRUE(test::bitwise_equal(test::state_by_id(batched), test::state_by_id(single)))
          << variant << ", " << threads << " threads";
      // Force, torque, |F| and the contact count: the batch's last step stores them, its
      // earlier ones left them in the sums (particle_update.hpp, FinishOut).
      expect_same_forces_and_springs(batched, single, variant);
    }
  }
}

// The thrown small bed landed (30,000 steps: 60 ms) and calmed by a background drag (10,000
// more): slow, most of its particles cold for the near pairs (near_pairs.hpp), with contacts and
// springs.
const Engine& landed_bed() {
  static const Engine landed = [] {
    auto [settings, particles] = test::small_bed();
    Engine falling(settings, particles);
    falling.run_steps(30000);
    settings.viscous_damping = 2e-3;  // kg/s: a 1 mm sphere's speed falls by e in about 0.7 ms
    Engine calming(settings, particles);
    calming.restore(falling.state(), falling.particles(), falling.pairs());
    calming.run_steps(10000);
    return calming;
  }();
  return landed;
}

// The force pass on the near pairs gives the whole list's bits: positions, velocities, forces,
// contact counts, springs (written back into the list) and energies, for every accumulation. On the
// landed bed through choices that carry springs from one to the next, with pairs left out; on the
// thrown bed (its fast particles hot: all their pairs near) and the draining bed (thrown at 1 m/s
// onto a plate, past a sink: the margin doubles, the whole list runs at times) through rebuilds
// that carry the springs to a new list.
TEST(DemEngine, NearPairsGiveTheWholeListsBits) {
  for (const char* scene : {"landed", "thrown", "draining"}) {
    const bool landed = scene == std::string("landed");
    auto [settings, particles] =
        scene == std::string("draining") ? test::draining_bed() : test::small_bed();
    for (const char* variant :
         {"ordered/static", "ordered/static/update=fused", "per-thread/static",
          "full-list/guided,1", "full-list/static/update=fused", "per-thread/dynamic,2",
          "atomic/static"}) {
      for (const int threads : {1, 3}) {
        if (!bits_fixed(variant, threads)) continue;
        EngineSettings s = settings;
        s.force_variant = parse_force_variant(variant);
        s.threads = threads;
        s.near_margin = 0.0;
        Engine whole(s, particles);
        s.near_margin = 0.02;
        Engine near(s, particles);
        if (landed) {
          const Engine& from = landed_bed();
          for (Engine* e : {&whole, &near})
            e->restore(from.state(), from.particles(), from.pairs());
        }
        const std::uint64_t choices_before = near.near_builds(), rebuilds_before = near.rebuilds();
        std::size_t fewer = 0;  // batches whose force pass ran on fewer pairs than the list's
        for (int batch = 0; batch < 14; ++batch) {
          whole.run_steps(50);
          near.run_steps(50);
          fewer += near.force_pairs().size() < near.pairs().size();
        }
        const std::string what =
            std::string(variant) + ", " + std::to_string(threads) + " threads, " + scene;
        EXPECT_EQ(whole.near_builds(), 0u);
        if (landed) {
          EXPECT_GT(near.near_builds() - choices_before, near.rebuilds() - rebuilds_before + 5)
              << what;
          EXPECT_EQ(fewer, 14u) << what;
        }
        EXPECT_EQ(near.rebuilds(), whole.rebuilds()) << what;
        EXPECT_TRUE(test::bitwise_equal(test::state_by_id(near), test::state_by_id(whole))) << what;
        expect_same_forces_and_springs(near, whole, what);
        EXPECT_EQ(near.energies().potential, whole.energies().potential) << what;
        EXPECT_EQ(near.large_overlap_count(), whole.large_overlap_count()) << what;
      }
    }
  }
}

// A batch that ends at rebuilds (dem run --retune, --until-discharged) ends right after the
// step that rebuilt the list, never leaves a drift pending, and gives the bits of single steps.
TEST(DemEngine, BatchesEndingAtRebuildsMatchSingleSteps) {
  auto [settings, particles] = test::small_bed();
  for (const int threads : {1, 3}) {
    EngineSettings s = settings;
    s.threads = threads;
    Engine batched(s, particles), single(s, particles);
    int ended_early = 0;
    while (batched.step_count() < 700) {
      const std::uint64_t rebuilds = batched.rebuilds();
      const std::uint64_t done = batched.run_steps(50, Engine::BatchEnd::kAtRebuild);
      ASSERT_GE(done, 1u);
      ASSERT_LE(done, 50u);
      EXPECT_LE(batched.rebuilds(), rebuilds + 1) << "a batch ran past a rebuild";
      EXPECT_EQ(done < 50, batched.rebuilds() == rebuilds + 1) << "step " << batched.step_count();
      ended_early += done < 50;
      while (single.step_count() + 1 < batched.step_count()) single.step();
      EXPECT_EQ(single.rebuilds(), rebuilds) << "the rebuild was not the batch's last step";
      single.step();
      ASSERT_EQ(single.rebuilds(), batched.rebuilds()) << "step " << batched.step_count();
    }
    EXPECT_GT(ended_early, 1);
    EXPECT_TRUE(test::bitwise_equal(test::state_by_id(batched), test::state_by_id(single)))
        << threads << " threads";
    EXPECT_TRUE(test::bitwise_equal(batched.particles().fx, single.particles().fx));
  }
}

// In a batch the drift's time moves from the update to the integration as a share of thread
// 0's finish loop, so no phase can go below zero, batch by batch, even on a scene of a few
// pieces where one stalled sample once stood for all of them (CI: a negative update made the
// force model's calibration zero).
TEST(DemEngine, BatchedPhaseTimesAreNeverNegative) {
  auto [settings, particles] = test::small_bed(20);
  for (const int threads : {1, 2}) {
    settings.threads = threads;
    Engine engine(settings, particles);
    for (int batch = 0; batch < 300; ++batch) {
      const PhaseTimes before = engine.phase_times();
      engine.run_steps(3);
      const PhaseTimes d = engine.phase_times() - before;
      for (const double phase :
           {d.neighbor_s, d.pair_forces_s, d.reduction_s, d.walls_s, d.update_s, d.integrate_s}) {
        ASSERT_GE(phase, 0.0) << "batch " << batch << ", " << threads << " threads";
      }
    }
  }
}

// A run that fails inside a batch stops at the same step with the same message (the particle,
// its position, the overlap or move) as one step at a time: a move too long (found by a drift
// done in the finish), overlaps too deep with a wall and between particles (the finish then
// does not drift).
// The forces the failed run leaves are the last step's, as single steps leave them, though the
// batch's finish had put them in its sums (FinishOut).
TEST(DemEngine, BatchedStepsFailWhereSingleStepsFail) {
  auto message = [](const EngineSettings& s, const Particles& p, bool batched) {
    Engine engine(s, p);
    try {
      if (batched) {
        engine.run_steps(5000);
      } else {
        for (int k = 0; k < 5000; ++k) engine.step();
      }
    } catch (const UnstableRun& e) {
      const Particles& q = engine.particles();
      std::vector<double> forces(8 * q.size());  // by id: force, torque, |F|, contacts
      for (std::size_t a = 0; a < q.size(); ++a) {
        const double f[8] = {q.fx[a],
                             q.fy[a],
                             q.fz[a],
                             q.tx[a],
                             q.ty[a],
                             q.tz[a],
                             q.force_magnitude[a],
                             static_cast<double>(q.contacts[a])};
        std::memcpy(&forces.at(std::size_t{8} * q.id[a]), f, sizeof f);
      }
      std::string digest(forces.size() * sizeof(double), '\0');
      std::memcpy(digest.data(), forces.data(), digest.size());
      return std::string(e.what()) + "\n" + digest;
    }
    return std::string("no failure");
  };
  // update=fused drifts pieces of particles among the pairs, once no later row reads them: on a
  // bed of 640 at one thread, among rows not yet computed (two blocks of rows; the head-on pair
  // below lies in the first).
  struct Case {
    std::uint32_t particles;
    int threads;
    const char* variant;
  };
  for (const Case& c : {Case{20, 2, "ordered/static"}, Case{20, 2, "ordered/static/update=fused"},
                        Case{640, 1, "ordered/static/update=fused"}}) {
    auto [settings, particles] = test::small_bed(c.particles);
    settings.threads = c.threads;
    settings.force_variant = parse_force_variant(c.variant);
    const std::string variant =
        std::string(c.variant) + ", " + std::to_string(c.particles) + " particles";
    EngineSettings pushed = settings;
    pushed.gravity = {2e5, 0, 0};  // along the periodic x: a move longer than skin/2 in time
    const std::string moved = message(pushed, particles, false);
    EXPECT_NE(moved.find("moved"), std::string::npos) << variant << ": " << moved;
    EXPECT_EQ(message(pushed, particles, true), moved) << variant;
    EngineSettings falling = settings;
    falling.gravity = {0, 0, -2e5};  // into the floor: the overlap with the wall passes 10 %
    const std::string into_wall = message(falling, particles, false);
    EXPECT_NE(into_wall.find("wall"), std::string::npos) << variant << ": " << into_wall;
    EXPECT_EQ(message(falling, particles, true), into_wall) << variant;
    Particles head_on = particles;  // particles 0 and 1 meet at 12 m/s: the overlap passes 10 %
    head_on.vx[0] = 6.0;
    head_on.vx[1] = -6.0;
    head_on.y[1] = head_on.y[0];
    head_on.z[1] = head_on.z[0];
    const std::string overlap = message(settings, head_on, false);
    EXPECT_NE(overlap.find("overlap"), std::string::npos) << variant << ": " << overlap;
    EXPECT_EQ(message(settings, head_on, true), overlap) << variant;
  }
  auto [falling, particles] = test::small_bed(20);
  falling.threads = 2;
  falling.gravity = {0, 0, -2e5};
  falling.force_variant = parse_force_variant("ordered/static/walls=serial");  // one thread's
  EXPECT_EQ(message(falling, particles, true), message(falling, particles, false));
}

TEST(DemEngine, BitIdenticalForAnySchedule) {
  auto [settings, particles] = test::small_bed(60);
  settings.threads = 2;
  Engine a(settings, particles);
  a.run_steps(200);
  omp_set_schedule(omp_sched_dynamic, 3);  // the engine's loops are static: no effect allowed
  Engine b(settings, particles);
  b.run_steps(200);
  omp_set_schedule(omp_sched_static, 0);
  EXPECT_TRUE(test::bitwise_equal(test::state_by_id(a), test::state_by_id(b)));
}

// A frictional contact that lasts across many rebuilds (a tiny skin forces them) gives the
// same motion as with a skin so large that the list is never rebuilt: the tangential spring
// survives each rebuild and reorder.
TEST(DemEngine, HistorySurvivesRebuildsAndReorders) {
  auto run = [](double skin) {
    EngineSettings s;
    s.law.restitution = 0.5;
    s.law.contact_time_s = 1e-4;
    s.law.friction = 0.8;
    s.gravity = {0, 0, -9.81};
    s.dt_s = 2e-6;
    s.skin = skin;
    s.warn_large_overlaps = false;
    s.domain.lo = {-1, -1, -1};
    s.domain.hi = {1, 1, 1};
    Wall floor;
    floor.name = "floor";
    s.walls.push_back(floor);
    Particles p;
    // A leaning two-sphere stack: the upper one (id 0, later in cell order, so a rebuild
    // reorders them) rests off-centre on the lower one, loading the pair's tangential spring.
    const double offset = 0.3e-3;
    p.add(0, 0, offset, 0, 1e-3 + std::sqrt(4e-6 - offset * offset) - 1e-6, 1e-3, 2500);
    p.add(1, 0, 0, 0, 1e-3, 1e-3, 2500);
    p.vx[0] = 0.2;
    p.vx[1] = 0.2;
    Engine engine(s, p);
    engine.run_steps(3000);
    return std::pair{test::state_by_id(engine), engine.rebuilds()};
  };
  const auto [often, rebuilds_often] = run(1e-6);
  const auto [never, rebuilds_never] = run(0.5);
  EXPECT_GT(rebuilds_often, 50u);
  EXPECT_EQ(rebuilds_never, 1u);
  ASSERT_EQ(often.size(), never.size());
  for (std::size_t k = 0; k < often.size(); ++k) {
    EXPECT_NEAR(often[k], never[k], 1e-9 * (1 + std::abs(never[k]))) << "component " << k;
  }
}

// The dashpot fed half-step velocities biases e by O(dt/t_c); synchronised ones converge
// faster. Each e is averaged over first-touch phases (the jump of the dashpot force at the first
// touch is an O(dt) error of either sign that depends on where in a step the touch falls).
TEST(DemEngine, SynchronisedVelocityRemovesHalfStepBias) {
  ContactLaw law;
  law.restitution = 0.5;
  law.contact_time_s = 1e-4;
  law.friction = 0;
  const double m = 2500 * 4.0 / 3.0 * std::numbers::pi * 1e-9;
  const double expected = predict_impact(pair_coefficients(law), 0.5 * m).restitution;
  std::vector<double> sync_error, half_error;
  for (const double divisor : {50.0, 100.0, 200.0}) {
    const double dt = 1e-4 / divisor;
    sync_error.push_back(
        std::abs(mean_restitution(law, 1e-3, 1e-3, 2500, 0.1, dt, VelocityInForces::kSynchronised) -
                 expected));
    half_error.push_back(std::abs(
        mean_restitution(law, 1e-3, 1e-3, 2500, 0.1, dt, VelocityInForces::kHalfStep) - expected));
    EXPECT_LT(sync_error.back(), half_error.back()) << "t_c/" << divisor;
  }
  for (std::size_t k = 0; k + 1 < half_error.size(); ++k) {
    // First order: halving dt halves the half-step bias; the synchronised error falls faster.
    EXPECT_NEAR(half_error[k] / half_error[k + 1], 2.0, 0.4);
    EXPECT_GT(sync_error[k] / sync_error[k + 1], half_error[k] / half_error[k + 1]);
  }
}

TEST(DemEngine, EnergyBalanceOfAFallingBed) {
  auto [settings, particles] = test::small_bed(60);
  Engine engine(settings, particles);
  const Energies e0 = engine.energies();
  EXPECT_NEAR(e0.dissipated, 0.0, 1e-18);
  engine.run_steps(2000);
  const Energies e1 = engine.energies();
  EXPECT_GT(e1.dissipated, 0.0);  // e < 1 and friction only remove energy
  EXPECT_NEAR(e1.kinetic + e1.potential + e1.dissipated, e0.kinetic + e0.potential,
              1e-12 * (e0.kinetic + std::abs(e0.potential)));
}

TEST(DemEngine, RefusesInitialOverlapsAndUnstableSteps) {
  auto [settings, particles] = test::small_bed(20);
  Particles overlapping = particles;
  overlapping.x[1] = overlapping.x[0] + overlapping.radius[0];  // deep overlap
  overlapping.y[1] = overlapping.y[0];
  overlapping.z[1] = overlapping.z[0];
  EXPECT_THROW(Engine engine(settings, overlapping), InputError);
  Particles in_floor = particles;
  in_floor.z[3] = 0.5 * in_floor.radius[3];
  EXPECT_THROW(Engine engine(settings, in_floor), InputError);
  EngineSettings big_dt = settings;
  big_dt.dt_s = 1e-4;
  try {
    Engine engine(big_dt, particles);
    FAIL() << "dt above the limit accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("stable limit"), std::string::npos) << e.what();
  }
}

TEST(DemContactLaw, ClampPredictionMatchesTheOdeSolvedFinely) {
  // Integrate x'' = -(k x + c x')/m* with the force clamped at 0 by RK4 at t_c/1e5.
  for (const double e : {0.1, 0.5, 0.9}) {
    ContactLaw law;
    law.restitution = e;
    law.contact_time_s = 1.0;
    const PairCoefficients c = pair_coefficients(law);
    const double m = 1.0, k = c.k_n(m), damp = c.c_n(m);
    double x = 0, v = 1, t = 0;
    const double h = 1e-5;
    auto acc = [&](double xx, double vv) { return -std::max(0.0, k * xx + damp * vv) / m; };
    while (t < 2.0) {
      const double a1 = acc(x, v), k1x = v;
      const double a2 = acc(x + 0.5 * h * k1x, v + 0.5 * h * a1), k2x = v + 0.5 * h * a1;
      const double a3 = acc(x + 0.5 * h * k2x, v + 0.5 * h * a2), k3x = v + 0.5 * h * a2;
      const double a4 = acc(x + h * k3x, v + h * a3), k4x = v + h * a3;
      x += h / 6 * (k1x + 2 * k2x + 2 * k3x + k4x);
      v += h / 6 * (a1 + 2 * a2 + 2 * a3 + a4);
      t += h;
      if (x <= 0) break;
    }
    EXPECT_NEAR(-v, predict_impact(c, m).restitution, 1e-4) << "e = " << e;
    EXPECT_GT(predict_impact(c, m).restitution, e);
  }
}

}  // namespace
}  // namespace contactlab::dem
