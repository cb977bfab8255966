// The DEM engine over MPI processes (contactlab::dem_mpi), run under `mpirun -np K` for K = 1-4
// (CTest label mpi): every owned particle's state after many steps, rebuilds and migrations is
// the one-process run's to the last bit, on the periodic bed with slabs across the periodic
// axis and along the open one, with a sink draining it, and for a sheared pair carried across a
// slab boundary by its motion (its friction force continuous: equal at every step). Rank 0
// compares.
#include <gtest/gtest.h>
#include <mpi.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "contactlab/dem/checkpoint.hpp"
#include "contactlab/dem/config.hpp"
#include "contactlab/dem/engine.hpp"
#include "contactlab/dem/force_variant.hpp"
#include "contactlab/dem/slabs.hpp"
#include "contactlab/dem_mpi/checkpoint.hpp"
#include "contactlab/dem_mpi/halo_exchange.hpp"
#include "contactlab/mpi/runtime.hpp"
#include "dem_support.hpp"

namespace contactlab::dem::test {
namespace {

using contactlab::dem::mpi::HaloExchange;
using contactlab::dem::mpi::HaloStats;

int rank() { return contactlab::mpi::rank_of(MPI_COMM_WORLD); }
int ranks() { return contactlab::mpi::size_of(MPI_COMM_WORLD); }

constexpr int kFields = 13;  // x, v, w, f (one-process fields the run is judged by)

// Every particle's state by id from one engine (one process): NaN where the sink took it.
std::vector<double> fields_by_id(const Particles& p, std::size_t ids,
                                 const std::vector<std::uint8_t>* ghost = nullptr) {
  std::vector<double> out(ids * kFields, std::nan(""));
  for (std::size_t a = 0; a < p.size(); ++a) {
    if (ghost != nullptr && (*ghost)[a] != 0) continue;
    const double v[kFields] = {p.x[a],  p.y[a],  p.z[a],  p.vx[a], p.vy[a], p.vz[a], p.wx[a],
                               p.wy[a], p.wz[a], p.fx[a], p.fy[a], p.fz[a], 0.0};
    std::memcpy(&out[std::size_t{kFields} * p.id[a]], v, sizeof v);
  }
  return out;
}

struct Outcome {
  std::vector<double> state;  // by id, on rank 0
  HaloStats stats;            // this rank's
  double removed_mass = 0.0;
  std::uint64_t run_particles = 0;
};

// The one-process run's outcome.
Outcome one_process(const EngineSettings& settings, const Particles& particles,
                    std::uint64_t steps) {
  Engine engine(settings, particles);
  engine.run_steps(steps);
  Outcome out;
  out.state = fields_by_id(engine.particles(), particles.size());
  out.removed_mass = engine.removed_mass();
  out.run_particles = engine.run_particles();
  return out;
}

// The same run decomposed into slabs along `axis` over every rank: each starts with the
// particles its slab owns; the owned states are summed onto rank 0 (NaN-free: every id is
// owned by exactly one rank or by none).
Outcome decomposed(const EngineSettings& settings, const Particles& particles, int axis,
                   std::uint64_t steps,
                   double rebalance_margin = std::numeric_limits<double>::infinity()) {
  const std::vector<double> work(particles.size(), 1.0);
  Slabs slabs = balance_slabs(particles, work, ranks(), axis, settings.domain);
  double max_r = 0.0;
  for (double r : particles.radius) max_r = std::max(max_r, r);
  EngineSettings mine = settings;
  if (mine.skin <= 0.0) mine.skin = 0.1 * 2.0 * max_r;  // the engine's default, from all
  const Particles own = slab_particles(slabs, particles, rank());
  HaloExchange halo(MPI_COMM_WORLD, slabs, 2.0 * max_r + mine.skin, rebalance_margin);
  Engine engine(mine, own, &halo);
  engine.run_steps(steps);
  const Particles& p = engine.particles();
  std::vector<std::uint8_t> ghost(p.size());
  for (std::size_t a = 0; a < p.size(); ++a) ghost[a] = halo.is_ghost(a) ? 1 : 0;
  std::vector<double> state = fields_by_id(p, particles.size(), &ghost);
  for (double& v : state) {
    if (std::isnan(v)) v = 0.0;  // not this rank's: adds nothing below
  }
  std::vector<double> mark(particles.size(), 0.0);  // how many ranks own each id
  for (std::size_t a = 0; a < p.size(); ++a) {
    if (ghost[a] == 0) mark[p.id[a]] = 1.0;
  }
  Outcome out;
  out.state.resize(state.size());
  std::vector<double> owners(mark.size());
  MPI_Reduce(state.data(), out.state.data(), static_cast<int>(state.size()), MPI_DOUBLE, MPI_SUM, 0,
             MPI_COMM_WORLD);
  MPI_Reduce(mark.data(), owners.data(), static_cast<int>(mark.size()), MPI_DOUBLE, MPI_SUM, 0,
             MPI_COMM_WORLD);
  if (rank() == 0) {
    for (std::size_t id = 0; id < owners.size(); ++id) {
      EXPECT_LE(owners[id], 1.0) << "particle " << id << " owned by two ranks";
      if (owners[id] == 0.0) {
        for (int f = 0; f < kFields; ++f) out.state[id * kFields + f] = std::nan("");
      }
    }
  }
  out.stats = halo.stats();
  out.removed_mass = halo.sum_over_ranks(engine.removed_mass());
  out.run_particles = engine.run_particles();
  return out;
}

// Rank 0's text on every rank (a file path rank 0 chose).
void broadcast(std::string& text) {
  int length = static_cast<int>(text.size());
  MPI_Bcast(&length, 1, MPI_INT, 0, MPI_COMM_WORLD);
  text.resize(static_cast<std::size_t>(length));
  MPI_Bcast(text.data(), length, MPI_CHAR, 0, MPI_COMM_WORLD);
}

// Bitwise, NaN (removed) equal to NaN; the first difference named.
void expect_same_bits(const std::vector<double>& want, const std::vector<double>& got) {
  ASSERT_EQ(want.size(), got.size());
  for (std::size_t k = 0; k < want.size(); ++k) {
    const bool both_nan = std::isnan(want[k]) && std::isnan(got[k]);
    if (both_nan) continue;
    ASSERT_EQ(std::bit_cast<std::uint64_t>(want[k]), std::bit_cast<std::uint64_t>(got[k]))
        << "particle " << k / kFields << " field " << k % kFields << ": " << want[k] << " vs "
        << got[k];
  }
}

class DemMpiAxes : public ::testing::TestWithParam<int> {};

TEST_P(DemMpiAxes, TheBedIsTheOneProcessRunToTheLastBit) {
  auto [settings, particles] = small_bed(150);
  constexpr std::uint64_t kSteps = 3000;  // about 15 rebuilds, particles crossing slabs
  const Outcome one = one_process(settings, particles, kSteps);
  const Outcome many = decomposed(settings, particles, GetParam(), kSteps);
  std::uint64_t migrated = many.stats.migrated;
  MPI_Allreduce(MPI_IN_PLACE, &migrated, 1, MPI_UINT64_T, MPI_SUM, MPI_COMM_WORLD);
  if (rank() == 0) {
    expect_same_bits(one.state, many.state);
    if (ranks() > 1) {
      EXPECT_GT(migrated, 0u) << "no particle changed slab: the test is too easy";
    }
  }
}

TEST_P(DemMpiAxes, ASinkDrainsTheSameParticlesAndMassWhileTheSlabsAreRebalanced) {
  auto [settings, particles] = draining_bed();  // dem_sink_gtest's scene
  constexpr std::uint64_t kSteps = 4000;
  const Outcome one = one_process(settings, particles, kSteps);
  // Re-balanced at every rebuild (margin 0): the particles move to new slabs as they drain.
  const Outcome many = decomposed(settings, particles, GetParam(), kSteps, 0.0);
  std::uint64_t rebalances = many.stats.rebalances;
  MPI_Allreduce(MPI_IN_PLACE, &rebalances, 1, MPI_UINT64_T, MPI_MAX, MPI_COMM_WORLD);
  if (rank() == 0) {
    if (ranks() > 1) {
      EXPECT_GT(rebalances, 0u) << "never re-balanced";
    }
    EXPECT_GT(one.removed_mass, 0.0) << "nothing drained: the test is too easy";
    // The same particles' masses, summed per rank first: equal to rounding.
    EXPECT_DOUBLE_EQ(one.removed_mass, many.removed_mass);
    EXPECT_EQ(one.run_particles, many.run_particles);
    expect_same_bits(one.state, many.state);
  }
}

// The drop box as its config builds it (216 spheres thrown into a periodic box with walls).
TEST_P(DemMpiAxes, TheDropBoxConfigIsTheOneProcessRunToTheLastBit) {
  const DemConfig config =
      read_dem_config(std::string(CONTACTLAB_SOURCE_DIR) + "/experiments/dem/drop-box.json");
  const Particles particles = make_particles(config);
  EngineSettings settings = config.settings;
  settings.warn_large_overlaps = false;
  constexpr std::uint64_t kSteps = 2500;
  const Outcome one = one_process(settings, particles, kSteps);
  const Outcome many = decomposed(settings, particles, GetParam(), kSteps, 0.1);
  if (rank() == 0) expect_same_bits(one.state, many.state);
}

// A hopper's window in miniature: the bed thrown onto a gate (a plane just above an orifice
// plate) that is removed after 1 ms, the particles then falling through the orifice into the sink,
// the slabs re-balanced as the work moves.
TEST_P(DemMpiAxes, AGateOpeningOverAnOrificeIsTheOneProcessRunToTheLastBit) {
  auto [settings, particles] = small_bed(150);
  settings.walls.clear();
  Wall gate;
  gate.name = "gate";
  gate.point = {0, 0, 0.0};
  gate.remove_at_s = 0.001;
  Wall plate;
  plate.kind = WallKind::kOrificePlate;
  plate.name = "plate";
  plate.point = {0.005, 0.005, -0.0005};
  plate.radius = 0.003;
  settings.walls = {gate, plate};
  settings.sink_below_z = -0.002;
  for (double& vz : particles.vz) vz -= 1.0;  // thrown onto the gate
  constexpr std::uint64_t kSteps = 6000;
  const Outcome one = one_process(settings, particles, kSteps);
  const Outcome many = decomposed(settings, particles, GetParam(), kSteps, 0.05);
  if (rank() == 0) {
    EXPECT_GT(one.removed_mass, 0.0) << "nothing left through the orifice: the test is too easy";
    EXPECT_EQ(one.run_particles, many.run_particles);
    expect_same_bits(one.state, many.state);
  }
}

// A checkpoint the ranks write together is the one one process would have written: one
// process restores it and continues to the same bits as the one-process run that never stopped.
TEST_P(DemMpiAxes, ACheckpointRestoresInOneProcessAndContinuesBitIdentically) {
  auto [settings, particles] = small_bed(150);
  constexpr std::uint64_t kBefore = 2000, kAfter = 1000;
  std::string path;
  if (rank() == 0) {
    path = ::testing::TempDir() + "/contactlab_dem_mpi_" + std::to_string(::getpid()) + ".chk";
  }
  broadcast(path);
  {
    const std::vector<double> work(particles.size(), 1.0);
    const Slabs slabs = balance_slabs(particles, work, ranks(), GetParam(), settings.domain);
    EngineSettings mine = settings;
    mine.skin = 0.1 * 2e-3;
    HaloExchange halo(MPI_COMM_WORLD, slabs, 2e-3 + mine.skin);
    Engine engine(mine, slab_particles(slabs, particles, rank()), &halo);
    engine.run_steps(kBefore);
    contactlab::dem::mpi::write_checkpoint(MPI_COMM_WORLD, engine, halo, 7, path);
  }
  if (rank() == 0) {
    EngineSettings one = settings;
    one.skin = 0.1 * 2e-3;
    Engine straight(one, particles);
    straight.run_steps(kBefore + kAfter);
    Engine restored(one, particles);
    EXPECT_EQ(read_checkpoint(restored, path), 7);
    EXPECT_EQ(restored.step_count(), kBefore);
    restored.run_steps(kAfter);
    expect_same_bits(fields_by_id(straight.particles(), particles.size()),
                     fields_by_id(restored.particles(), particles.size()));
    std::remove(path.c_str());
  }
}

// A one-process checkpoint resumed on every rank: the start rebuilds the list (another order,
// other roundings), so the positions after 1,000 more steps are compared with the one-process
// restore within a bound, not bit for bit.
TEST_P(DemMpiAxes, AOneProcessCheckpointResumesOnTheRanks) {
  auto [settings, particles] = small_bed(150);
  settings.skin = 0.1 * 2e-3;
  constexpr std::uint64_t kBefore = 2000, kAfter = 1000;
  std::string path;
  if (rank() == 0) {
    path = ::testing::TempDir() + "/contactlab_dem_resume_" + std::to_string(::getpid()) + ".chk";
    Engine first(settings, particles);
    first.run_steps(kBefore);
    write_checkpoint(first, 3, path);
  }
  broadcast(path);
  Particles config = particles;
  config.set_wall_count(settings.walls.size());
  CheckpointParts parts = read_checkpoint_parts(path, config);
  const SlabPlan plan = plan_slabs(parts.particles, parts.pairs, settings, ranks(), GetParam());
  CarriedSprings springs;
  collect_springs(parts.particles, parts.pairs, springs);
  EXPECT_GT(springs.size(), 0u);
  Engine::State state = parts.state;
  if (rank() != 0) state.initial_energy = 0.0;
  HaloExchange halo(MPI_COMM_WORLD, plan.slabs, plan.halo);
  halo.seed_springs(springs);
  Engine engine(settings, slab_particles(plan.slabs, parts.particles, rank()), &halo, &state);
  EXPECT_EQ(engine.step_count(), kBefore);
  engine.run_steps(kAfter);
  std::vector<double> got(particles.size() * kFields, 0.0);
  const Particles& p = engine.particles();
  for (std::size_t a = 0; a < p.size(); ++a) {
    if (halo.is_ghost(a)) continue;
    got[std::size_t{kFields} * p.id[a]] = p.x[a];
    got[std::size_t{kFields} * p.id[a] + 1] = p.y[a];
    got[std::size_t{kFields} * p.id[a] + 2] = p.z[a];
  }
  MPI_Allreduce(MPI_IN_PLACE, got.data(), static_cast<int>(got.size()), MPI_DOUBLE, MPI_SUM,
                MPI_COMM_WORLD);
  const Energies resumed = engine.energies();
  if (rank() == 0) {
    Engine restored(settings, particles);
    read_checkpoint(restored, path);
    restored.run_steps(kAfter);
    const std::vector<double> want = fields_by_id(restored.particles(), particles.size());
    double largest = 0.0;
    for (std::size_t id = 0; id < particles.size(); ++id) {
      for (int f = 0; f < 3; ++f) {
        // A periodic position may differ by a period: the resumed run wrapped it at its start.
        double d = want[id * kFields + f] - got[id * kFields + f];
        if (settings.domain.periodic[f]) {
          const double period = settings.domain.length(f);
          d -= period * std::round(d / period);
        }
        largest = std::max(largest, std::abs(d));
      }
    }
    EXPECT_LT(largest, 1e-9) << "largest position difference " << largest << " m";
    std::printf("resumed on %d ranks: largest position difference after %llu steps %.3g m\n",
                ranks(), static_cast<unsigned long long>(kAfter), largest);
    const Energies want_energy = restored.energies();
    EXPECT_NEAR(resumed.kinetic, want_energy.kinetic, 1e-9 * want_energy.kinetic);
    std::remove(path.c_str());
  }
}

INSTANTIATE_TEST_SUITE_P(Slabs, DemMpiAxes, ::testing::Values(0, 2),
                         [](const ::testing::TestParamInfo<int>& axis) {
                           return axis_name(axis.param);
                         });

// Every accumulation of the force pass, with its walls and update variants, on two threads a
// rank: those whose sums have a fixed order (ordered, full-list) give the one-process run's bits;
// the shared ones (per-thread, atomic) differ from it by round-off only, as they do between
// thread counts in one process (dem_force_variant_gtest's bound).
TEST(DemMpiVariants, EveryForceVariantRunsAsInOneProcess) {
  for (const char* text :
       {"ordered/static", "ordered/static/walls=serial", "ordered/static/update=fused",
        "full-list/dynamic,4", "per-thread/dynamic,4", "atomic/guided,2",
        "per-thread/dynamic,1/walls=serial"}) {
    auto [settings, particles] = small_bed(150);
    settings.threads = 2;
    settings.force_variant = parse_force_variant(text);
    constexpr std::uint64_t kSteps = 600;
    const Outcome one = one_process(settings, particles, kSteps);
    const Outcome many = decomposed(settings, particles, 2, kSteps);
    if (rank() != 0) continue;
    if (thread_count_invariant(settings.force_variant)) {
      SCOPED_TRACE(text);
      expect_same_bits(one.state, many.state);
      continue;
    }
    double worst = 0.0;
    for (std::size_t k = 0; k < one.state.size(); ++k) {
      worst = std::max(
          worst, std::abs(one.state[k] - many.state[k]) / std::max(1.0, std::abs(one.state[k])));
    }
    EXPECT_LT(worst, 1e-9) << text;
  }
}

// Two spheres pressed together and sheared (opposite tangential velocities, spinning), drifting
// together across the slab boundaries: the rank that takes them over must continue their
// tangential spring, not restart it. Equal at every step (forces included) to the one-process
// run means the friction force never jumped.
TEST(DemMpiMigration, AShearedPairKeepsItsFrictionAcrossTheBoundary) {
  EngineSettings settings;
  settings.law.restitution = 0.3;
  settings.law.contact_time_s = 1e-4;
  settings.law.friction = 0.5;
  settings.dt_s = 2e-6;
  settings.domain.lo = {-0.02, -0.02, -0.02};
  settings.domain.hi = {0.02, 0.02, 0.02};
  settings.warn_large_overlaps = false;
  settings.gravity = {0, 0, -9.81};
  Wall floor;
  floor.name = "floor";
  floor.point = {0, 0, -1e-3};
  settings.walls.push_back(floor);
  Particles particles;
  // Sphere 1 rests on sphere 0, which rests on the floor; both slide along x (across x = 0 in
  // about 2 ms) spinning the same way about x, so that their contact slips (sheared) and
  // stays on, its spring at the Coulomb limit. Two more spheres far left and right keep every slab
  // in use.
  particles.add(0, 0, -0.004, 0.0, 0.0, 1e-3, 2500.0);
  particles.add(1, 0, -0.004, 0.0, 2e-3, 1e-3, 2500.0);
  particles.add(2, 0, -0.015, 0.0, 0.0, 1e-3, 2500.0);
  particles.add(3, 0, 0.015, 0.0, 0.0, 1e-3, 2500.0);
  for (std::uint32_t k : {0u, 1u}) particles.vx[k] = 2.0;
  particles.wx[0] = 50.0;  // the contact slips at 0.1 m/s: friction at the Coulomb limit
  particles.wx[1] = 50.0;
  // Slabs cut at x = 0 (the pair's start is left of it for any rank count from 2 on).
  std::vector<double> work(particles.size(), 1.0);
  constexpr std::uint64_t kSteps = 2000;
  Engine reference(settings, particles);
  std::vector<std::vector<double>> want;
  for (std::uint64_t s = 0; s < kSteps; s += 100) {
    reference.run_steps(100);
    want.push_back(fields_by_id(reference.particles(), particles.size()));
  }
  EXPECT_GT(reference.particles().x[reference.index_of(0)], 0.0) << "the pair did not cross";
  // The decomposed run, compared every 100 steps.
  Slabs slabs = balance_slabs(particles, work, ranks(), 0, settings.domain);
  if (ranks() >= 2) {
    slabs.cuts[ranks() / 2] = 0.0;
    for (int r = 1; r < ranks(); ++r) {
      slabs.cuts[r] = r < ranks() / 2   ? -0.01 - 0.001 * r
                      : r > ranks() / 2 ? 0.01 + 0.001 * r
                                        : 0.0;
    }
  }
  const Particles own = slab_particles(slabs, particles, rank());
  EngineSettings mine = settings;
  mine.skin = 0.1 * 2e-3;
  HaloExchange halo(MPI_COMM_WORLD, slabs, 2e-3 + mine.skin);
  Engine engine(mine, own, &halo);
  for (std::size_t round = 0; round < want.size(); ++round) {
    engine.run_steps(100);
    const Particles& p = engine.particles();
    std::vector<double> state(particles.size() * kFields, 0.0);
    for (std::size_t a = 0; a < p.size(); ++a) {
      if (halo.is_ghost(a)) continue;
      const double v[kFields] = {p.x[a],  p.y[a],  p.z[a],  p.vx[a], p.vy[a], p.vz[a], p.wx[a],
                                 p.wy[a], p.wz[a], p.fx[a], p.fy[a], p.fz[a], 0.0};
      std::memcpy(&state[std::size_t{kFields} * p.id[a]], v, sizeof v);
    }
    MPI_Allreduce(MPI_IN_PLACE, state.data(), static_cast<int>(state.size()), MPI_DOUBLE, MPI_SUM,
                  MPI_COMM_WORLD);
    if (rank() == 0) expect_same_bits(want[round], state);
  }
  std::uint64_t springs = halo.stats().migrated_springs;
  MPI_Allreduce(MPI_IN_PLACE, &springs, 1, MPI_UINT64_T, MPI_SUM, MPI_COMM_WORLD);
  if (ranks() > 1) {
    EXPECT_GT(springs, 0u) << "no spring migrated with the pair";
  }
}

}  // namespace
}  // namespace contactlab::dem::test

// GoogleTest under MPI: every rank runs the tests, rank 0 prints (every rank with DEBUG_ALL set,
// e.g. `mpirun -x DEBUG_ALL=1`, to see an exception only one rank met); every rank exits with
// the worst outcome.
int main(int argc, char** argv) {
  const contactlab::mpi::Session session(&argc, &argv);
  ::testing::InitGoogleTest(&argc, argv);
  if (contactlab::mpi::rank_of(MPI_COMM_WORLD) != 0 && std::getenv("DEBUG_ALL") == nullptr) {
    auto& listeners = ::testing::UnitTest::GetInstance()->listeners();
    delete listeners.Release(listeners.default_result_printer());
  }
  const int failed = RUN_ALL_TESTS();
  int any = 0;
  MPI_Allreduce(&failed, &any, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
  return any;
}
