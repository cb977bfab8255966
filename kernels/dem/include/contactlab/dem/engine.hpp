// The DEM engine: velocity Verlet over spheres with the linear spring-dashpot law, walls,
// gravity and periodic sides, deterministic for any thread count (per-pair force buffer
// gathered per particle in a fixed order), with run-time stability checks.
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "contactlab/dem/contact_law.hpp"
#include "contactlab/dem/force_variant.hpp"
#include "contactlab/dem/halo.hpp"
#include "contactlab/dem/near_pairs.hpp"
#include "contactlab/dem/pair_list.hpp"
#include "contactlab/dem/particles.hpp"
#include "contactlab/dem/row_ranges.hpp"
#include "contactlab/dem/walls.hpp"

namespace contactlab::dem {

// Which velocity the dashpots and the tangential spring see at step n + 1.
// kSynchronised: v(t + dt) predicted as v(t + dt/2) + a(t) dt/2 (error O(dt^2)); kHalfStep:
// v(t + dt/2) as in LAMMPS' default, which biases e by O(dt / t_c).
enum class VelocityInForces { kSynchronised, kHalfStep };

// The instruction set the step's hot loops (force pass, finish, drift) run on: each is compiled
// for all three and chosen at run time, so that a portable build runs as fast as a native one
// (src/dem_isa.hpp). Every set gives the same bits: the same operations in the same order,
// without fused multiply-adds.
enum class StepIsa { kBaseline, kAvx2, kAvx512 };
// "baseline" (no AVX: the build's SSE level), "AVX2", "AVX-512".
std::string to_string(StepIsa isa);
// The set this process runs the step on: the detection's choice (contactlab/kernels/simd.hpp:
// the best the CPU has, or CONTACTLAB_SIMD / select_simd_target), "AVX3..." as AVX-512, "AVX2"
// as AVX2, anything else ("SSE4", "off", ...) as the baseline. On a CPU other than x86-64,
// the baseline.
StepIsa step_isa();

struct EngineSettings {
  ContactLaw law;
  std::vector<Wall> walls;
  Domain domain;
  Vec3 gravity{0, 0, 0};  // m/s^2
  double dt_s = 1e-6;
  double skin = 0.0;  // m; 0 = 0.1 x the largest diameter
  // The force pass runs on the near pairs (near_pairs.hpp): those within a margin of touching,
  // chosen again from the neighbour list whenever a pair left out may have closed its gap. The
  // margin starts at this fraction of the skin and follows how long a choice lasts. The forces
  // are the same bits with or without; 0 runs on the whole list. Not with a halo (a ghost's
  // moves are its owner's), where the whole list runs.
  double near_margin = 0.1;
  VelocityInForces velocity_in_forces = VelocityInForces::kSynchronised;
  // Initial overlaps above this fraction of the smaller diameter are refused (InputError).
  double initial_overlap_tolerance = 0.01;
  int threads = 1;
  bool warn_large_overlaps = true;
  // Background drag F = -c v [kg/s] on every particle; 0 = off. For settling beds only (it
  // breaks the energy balance: its work counts as dissipated).
  double viscous_damping = 0.0;
  // How the force pass runs in parallel (force_variant.hpp). The default, ordered with the
  // update separate, is bit-identical for any thread count; PhaseTimes then splits the pair
  // forces from walls + finish + kick (update=fused counts them in the pair forces).
  ForceVariant force_variant;
  // The sink (LIGGGHTS `delete` region): particles whose centre is below this height [m] leave
  // the run at the next neighbour-list rebuild, their mass counted (sink.cpp). -inf = no sink.
  double sink_below_z = -std::numeric_limits<double>::infinity();
  // Whether the domain's box bounds the particles on its non-periodic axes (a config's
  // `domain`): a particle flung farther than one box length outside it (along a non-periodic
  // axis) is an UnstableRun naming it at the next rebuild, or an InputError at the start, not a
  // run whose grid and memory grow with it. Within that margin it runs on: below a hopper's
  // orifice the outflow spreads wider than the silo's box until the sink takes it. Off for
  // scenes built in code, whose domain matters for its periodic axes only.
  bool domain_bounds_particles = false;
};

// Phase times of step() [s], summed since construction: the neighbour list (candidates, in
// parallel; the carrying of springs and the reorder on one thread), the
// pair forces, the reduction (the j sides other threads left, or the per-thread arrays' sum),
// the walls when one thread does them (walls=serial), the update (walls when parallel,
// gravity, kick), the integration (half kick, drift, checks; inside run_steps the drift of
// the next step runs in the finish's pass, and its share of thread 0's time there, sampled on
// every eighth piece of particles, counts here, not in the update). With update=fused the pairs,
// reduction and update are one phase, counted in pair_forces_s.
struct PhaseTimes {
  double neighbor_s = 0.0, pair_forces_s = 0.0, reduction_s = 0.0, walls_s = 0.0, update_s = 0.0,
         integrate_s = 0.0;
  double total_s() const {
    return neighbor_s + pair_forces_s + reduction_s + walls_s + update_s + integrate_s;
  }
  // The force pass: everything between two integrations but the neighbour list.
  double force_s() const { return pair_forces_s + reduction_s + walls_s + update_s; }
  // Phase by phase: `after - before` is the time of the steps between two readings, and
  // `/ steps` their time per step.
  friend PhaseTimes operator-(const PhaseTimes& a, const PhaseTimes& b) {
    return {a.neighbor_s - b.neighbor_s,   a.pair_forces_s - b.pair_forces_s,
            a.reduction_s - b.reduction_s, a.walls_s - b.walls_s,
            a.update_s - b.update_s,       a.integrate_s - b.integrate_s};
  }
  friend PhaseTimes operator/(const PhaseTimes& a, double divisor) {
    return {a.neighbor_s / divisor, a.pair_forces_s / divisor, a.reduction_s / divisor,
            a.walls_s / divisor,    a.update_s / divisor,      a.integrate_s / divisor};
  }
};

struct Energies {
  double kinetic = 0.0;     // J: translation + rotation
  double potential = 0.0;   // J: gravity (relative to the origin) + elastic springs
  double dissipated = 0.0;  // J: initial total - current total (work of moving walls included)
};

// Thrown when a run becomes unstable (NaN, overlap above 10 % of the smaller diameter, a move
// longer than skin/2 in one step); the message names the particle, its position and the step.
class UnstableRun : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// What an output (a frame, a picture, a discharge row) shows of a run at one step: one
// process's engine (Engine::snapshot), or a decomposed run's particles gathered on one rank
// with the counters summed over the ranks (dem_mpi/gather.hpp).
struct Snapshot {
  const Particles& particles;  // the run's present particles, in any order
  const EngineSettings& settings;
  double time_s = 0.0;
  std::uint64_t step = 0;
  Energies energies;
  std::uint64_t removed_count = 0;  // particles the sink removed so far, and their mass [kg]
  double removed_mass = 0.0;
};

class Engine {
 public:
  // Checks dt against the stable limit (InputError stating it), builds the neighbour list,
  // refuses initial overlaps beyond the tolerance and computes the initial forces.
  // With a halo (halo.hpp, not owned, outliving the engine), `particles` are this process's part
  // of a decomposed run (possibly none): every rebuild, force evaluation and energy is agreed
  // with the other processes through it, so every call below that steps or sums is collective.
  struct State;  // a checkpoint's time and counters (below)
  // With `resume`, the run continues from a checkpoint's state (a decomposed run restarting):
  // the particles carry their velocities, forces and wall springs, the halo the pairs' springs
  // (HaloExchange::seed_springs); no overlap check, no force evaluation, the counters the
  // state's. Unlike restore(), the start rebuilds the list (the order and the next rebuilds
  // then differ from the run that wrote the checkpoint: the same physics, other roundings).
  Engine(EngineSettings settings, Particles particles, Halo* halo = nullptr,
         const State* resume = nullptr);

  void step();
  // Where a batch of run_steps may end early: kAtRebuild ends it after a step that rebuilt
  // the neighbour list, the only step where the sink takes particles and the pair list a
  // re-tuner prices can change (dem run --retune, --until-discharged check after it).
  enum class BatchEnd { kAfterSteps, kAtRebuild };
  // Up to `steps` steps, each one's finish (update=separate) followed by the next one's drift
  // in the same pass over the particles (their arrays read once, not twice): the same bits as
  // calling step() as often; between the calls nothing is half-stepped. Fewer when the sink
  // has taken every particle or, with kAtRebuild, after a rebuild. Returns the steps run.
  std::uint64_t run_steps(std::uint64_t steps, BatchEnd end = BatchEnd::kAfterSteps);

  const Particles& particles() const { return particles_; }
  // The neighbour list with every pair's spring as of the last step.
  const PairList& pairs() const {
    store_pair_springs();
    return pairs_;
  }
  // What the force pass runs on: the near pairs, or the whole list (near_margin 0, a halo).
  const PairList& force_pairs() const { return near_on_ ? near_.list : pairs_; }
  std::uint64_t near_builds() const { return near_.builds; }
  const EngineSettings& settings() const { return settings_; }
  const PairCoefficients& coefficients() const { return coefficients_; }
  double time_s() const { return time_s_; }
  std::uint64_t step_count() const { return step_; }
  std::uint64_t rebuilds() const { return rebuilds_; }
  // Particles times steps since construction (each step counts the particles it started with;
  // with a halo, this process's own).
  std::uint64_t particle_steps() const { return particle_steps_; }
  const PhaseTimes& phase_times() const { return phases_; }
  // Index of the particle with stable id `id` in the current order; kRemoved once the sink took
  // it (ids stay those of the config: after removals they are no longer dense).
  static constexpr std::uint32_t kRemoved = UINT32_MAX;
  std::uint32_t index_of(std::uint32_t id) const { return index_of_id_[id]; }
  // One more than the largest stable id the run started with (arrays indexed by id use it).
  std::size_t id_capacity() const { return index_of_id_.size(); }
  // Particles the sink removed so far, and their mass [kg].
  std::uint64_t removed_count() const { return removed_count_; }
  double removed_mass() const { return removed_mass_; }
  // With a halo, over every process (collective), ghosts not counted.
  Energies energies() const;
  // The run as an output shows it; one process only (a decomposed run gathers its own:
  // with a halo this throws std::logic_error).
  Snapshot snapshot() const;
  // The particles of the run: this engine's, or with a halo every process's owned ones
  // (as of the last rebuild).
  std::uint64_t run_particles() const { return run_particles_; }
  // Pairs with overlap above 1 % of the smaller diameter, counted over all steps (and whether
  // the one warning has been given).
  std::uint64_t large_overlap_count() const { return large_overlaps_; }
  double stable_dt() const { return stable_dt_; }

  // Checkpoint support: the complete state (particles, pairs with history, counters).
  struct State {
    double time_s = 0.0;
    std::uint64_t step = 0, rebuilds = 0, large_overlaps = 0;
    double initial_energy = 0.0;
    std::uint64_t removed_count = 0;
    double removed_mass = 0.0;
    // The time is base + (step - base_step) dt, not a running sum; a restart that keeps the
    // base (same dt) gives the unbroken run's times to the last bit.
    double base_time_s = 0.0;
    std::uint64_t base_step = 0;
  };
  State state() const {
    return {time_s_,        step_,         rebuilds_,    large_overlaps_, initial_energy_,
            removed_count_, removed_mass_, base_time_s_, base_step_};
  }
  // Replaces the state with a checkpoint's (particles and pairs as saved, CSR rebuilt).
  void restore(const State& state, Particles particles, PairList pairs);

  void set_threads(int threads) { settings_.threads = threads; }
  // The instruction set of the step's hot loops: step_isa() when the engine was made.
  StepIsa instruction_set() const { return step_isa_; }
  // From the next step on (e.g. re-tuned at a rebuild); throws InputError for a variant that
  // breaks a rule (force_variant.hpp).
  void set_force_variant(const ForceVariant& variant);

 private:
  void rebuild();
  void set_counters(const State& state);  // time, step and the counters (restore, resume)
  Energies local_energies() const;        // this process's particles (dissipated not set)
  // sink.cpp: removes the particles below the sink level from the particle arrays. True if it
  // removed any: the old list's touching springs are then in carried_ by stable ids (unless a
  // halo put them there already) and the list is emptied.
  bool remove_sunk_particles();
  // With domain_bounds_particles: the first particle (in order) flung more than a box length
  // outside the box named (InputError at the start, else UnstableRun).
  void check_containment() const;
  void index_ids();
  // kin_ from the particle arrays (after a reorder or restore), with the velocities the forces
  // see predicted as v + a kick.
  void refresh_kinematics(double kick);
  double prediction_kick() const;  // dt/2 with synchronised velocities, else 0
  void index_wall_reach();         // wall_reach_ for the particles as they stand
  void index_pair_constants();     // pairs_.m_star and inv_kt for the list as it stands
  // One step; with drift_next, the finish also drifts the particles into the next step, which
  // must follow at once (advance() then skips its drift), unless the step rebuilds and
  // end_at_rebuild. Returns whether it rebuilt the neighbour list.
  bool advance(bool drift_next, bool end_at_rebuild = false);
  void compute_forces(bool final_kick, bool drift_next = false);
  // engine_isa.cpp: compute_forces and advance's drift for each instruction set (specialised
  // there, once per set); compute_forces and advance call step_isa_'s.
  template <StepIsa kIsa>
  void compute_forces_on(bool final_kick, bool drift_next);
  template <StepIsa kIsa>
  void drift_on(double& max_disp_sq, double& max_step_sq, std::uint32_t& bad);
  void check_pair_overlap(std::size_t k) const;
  [[noreturn]] void fail(const std::string& what, std::uint32_t index) const;

  EngineSettings settings_;
  Halo* halo_ = nullptr;
  CarriedSprings carried_;  // with a halo or after the sink: the springs a rebuild carries
  std::uint64_t run_particles_ = 0;
  StepIsa step_isa_ = step_isa();
  PairCoefficients coefficients_;
  Particles particles_;
  // Its springs are stale while pair_springs_stale_: the force pass keeps them in near_.list,
  // and store_pair_springs writes them back (mutable: pairs() shows them).
  mutable PairList pairs_;
  mutable bool pair_springs_stale_ = false;
  void store_pair_springs() const;
  NearPairs near_;
  bool near_on_ = false;
  double near_fraction_ = 0.0;       // the margin now, a fraction of the skin
  std::uint64_t near_built_at_ = 0;  // the step of the last choice
  static constexpr double kMinNearFraction = 1.0 / 32;
  PairList& force_list() { return near_on_ ? near_.list : pairs_; }
  // The near pairs chosen anew from the neighbour list: just rebuilt or restored (its springs
  // are the ones), or as it was (the springs are the near pairs').
  void choose_near_pairs(bool list_rebuilt);
  NeighborBuilder builder_;
  RadixBuffers near_sort_;
  std::vector<std::uint32_t> index_of_id_;
  double time_s_ = 0.0;
  std::uint64_t step_ = 0, rebuilds_ = 0, large_overlaps_ = 0, particle_steps_ = 0;
  std::uint64_t removed_count_ = 0;
  double removed_mass_ = 0.0;
  bool warned_ = false;
  double stable_dt_ = 0.0, initial_energy_ = 0.0;
  double base_time_s_ = 0.0;  // time and step of the last restore: t = base + (step - base) dt
  std::uint64_t base_step_ = 0;
  PhaseTimes phases_;
  // Set when the last finish also drifted the next step (its largest displacement since the
  // list build and the first particle it failed, as the drift reports them).
  bool drifted_ = false;
  double drifted_disp_sq_ = 0.0, drifted_step_sq_ = 0.0;
  std::uint32_t drifted_bad_ = UINT32_MAX;
  // Set when that finish left force, torque, |F| and the contact count in acc_, not in the
  // particle arrays (it drifted the next step: before the next finish only a rebuild or a
  // failure reads them); store_forces puts them there.
  bool forces_in_sums_ = false;
  void store_forces();
  AlignedVector<double> kin_;  // what the pair loop reads per particle, side by side
  // Per particle, bit w set when wall w may touch it before the next rebuild.
  std::vector<std::uint32_t> wall_reach_;
  std::vector<std::uint32_t> wall_reachers_;  // the particles with a bit in wall_reach_, in order
  AlignedVector<double> acc_;  // per particle: the force pass's pair sums (detail::kAccStride)
  std::vector<std::vector<double>> block_scratch_;  // per thread: the force pass's pair block
  std::vector<AlignedVector<double>> thread_acc_;   // per thread: sums (per-thread accumulation)
  RowRanges row_ranges_;  // the ordered pass's range per thread, by the threads' speeds
  // The ordered pass's j sides for other threads' particles: threads x threads lists.
  std::vector<LeftJSides> left_j_sides_;
  RowsDone rows_done_;                // the ordered pass's signals: each thread's rows done
  std::uint64_t ordered_passes_ = 0;  // the ordered passes so far: the signals' pass numbers
};

}  // namespace contactlab::dem
