// Velocity Verlet with synchronised velocities in the forces, and the deterministic force
// evaluation: pair forces into a per-pair buffer, gathered per particle through its CSR.
#include "contactlab/dem/engine.hpp"

#include <fmt/core.h>
#include <omp.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "contactlab/kernels/count_then_fill.hpp"
#include "contactlab/kernels/error.hpp"
#include "pair_block.hpp"

namespace contactlab::dem {
using detail::kAccStride;
using detail::kKinStride;

// engine_isa.cpp defines them, once per instruction set.
template <>
void Engine::compute_forces_on<StepIsa::kBaseline>(bool final_kick, bool drift_next);
template <>
void Engine::compute_forces_on<StepIsa::kAvx2>(bool final_kick, bool drift_next);
template <>
void Engine::compute_forces_on<StepIsa::kAvx512>(bool final_kick, bool drift_next);
template <>
void Engine::drift_on<StepIsa::kBaseline>(double& max_disp_sq, double& max_step_sq,
                                          std::uint32_t& bad);
template <>
void Engine::drift_on<StepIsa::kAvx2>(double& max_disp_sq, double& max_step_sq, std::uint32_t& bad);
template <>
void Engine::drift_on<StepIsa::kAvx512>(double& max_disp_sq, double& max_step_sq,
                                        std::uint32_t& bad);

Engine::Engine(EngineSettings settings, Particles particles, Halo* halo, const State* resume)
    : settings_(std::move(settings)),
      halo_(halo),
      coefficients_(pair_coefficients(settings_.law)),
      particles_(std::move(particles)) {
  Particles& p = particles_;
  const std::size_t n = p.size();
  if (n == 0 && halo_ == nullptr) throw InputError("no particles");
  double max_d = 0.0, min_m = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < n; ++k) {
    max_d = std::max(max_d, 2.0 * p.radius[k]);
    min_m = std::min(min_m, p.mass[k]);
  }
  if (halo_ != nullptr) {  // every process decides on the run's extremes
    max_d = halo_->max_over_ranks(max_d);
    min_m = -halo_->max_over_ranks(-min_m);
    if (max_d == 0.0) throw InputError("no particles");
  }
  if (settings_.skin <= 0.0) settings_.skin = 0.1 * max_d;
  // The stiffest contact: two of the lightest particles (m* = m/2) or one on a wall (m* = m);
  // in (e, t_c) form both have the same w0, in (k_n, gamma_n) form the pair is stiffer.
  stable_dt_ = stable_time_step(coefficients_, 0.5 * min_m);
  if (!settings_.walls.empty())
    stable_dt_ = std::min(stable_dt_, stable_time_step(coefficients_, min_m));
  if (!(settings_.dt_s > 0) || settings_.dt_s > stable_dt_) {
    throw InputError(
        fmt::format("time step {:.6g} s is above the stable limit {:.6g} s "
                    "(2/w0 for the stiffest pair; recommended t_c/50 = {:.6g} s)",
                    settings_.dt_s, stable_dt_, contact_time(coefficients_, 0.5 * min_m) / 50.0));
  }
  if (resume == nullptr) {
    p.set_wall_count(settings_.walls.size());
  } else {
    if (p.wall_spring.size() != 3 * settings_.walls.size()) {
      throw InputError("the resumed particles' wall springs do not match the config's walls");
    }
    set_counters(*resume);  // before the build: the walls' reach at the resumed time
  }
  rebuild();
  // Resumed: the particles carry their forces, springs and velocities as the checkpoint saved
  // them; computing the forces again would advance every spring by one more step.
  if (resume != nullptr) return;
  // Initial overlaps: pairs and walls.
  const double tol = settings_.initial_overlap_tolerance;
  for (std::size_t k = 0; k < pairs_.size(); ++k) {
    const std::uint32_t i = pairs_.i[k], j = pairs_.j[k];
    const auto& sh = pairs_.shift[pairs_.image[k]];
    const double dx = p.x[i] - p.x[j] - sh[0], dy = p.y[i] - p.y[j] - sh[1],
                 dz = p.z[i] - p.z[j] - sh[2];
    const double overlap = p.radius[i] + p.radius[j] - std::sqrt(dx * dx + dy * dy + dz * dz);
    if (overlap > tol * 2.0 * std::min(p.radius[i], p.radius[j])) {
      throw InputError(
          fmt::format("particles {} and {} overlap by {:.3g} m at start (more than "
                      "{} of the smaller diameter)",
                      p.id[i], p.id[j], overlap, tol));
    }
  }
  for (std::size_t w = 0; w < settings_.walls.size(); ++w) {
    for (std::size_t k = 0; k < n; ++k) {
      Vec3 q;
      if (!closest_point(settings_.walls[w], 0.0, {p.x[k], p.y[k], p.z[k]}, q)) continue;
      const double dist = std::hypot(p.x[k] - q[0], p.y[k] - q[1], p.z[k] - q[2]);
      if (p.radius[k] - dist > tol * 2.0 * p.radius[k]) {
        throw InputError(fmt::format("particle {} overlaps wall '{}' by {:.3g} m at start", p.id[k],
                                     settings_.walls[w].name, p.radius[k] - dist));
      }
    }
  }
  refresh_kinematics(0.0);  // the first forces see the initial velocities
  compute_forces(false);
  const Energies e = local_energies();  // with a halo, this process's share
  initial_energy_ = e.kinetic + e.potential;
}

namespace {

// Particle k's linear and angular accelerations from its last forces and torques.
struct Accelerations {
  double ax, ay, az, bx, by, bz;
};
Accelerations accelerations(const Particles& p, std::size_t k) {
  return {p.fx[k] * p.inv_mass[k],    p.fy[k] * p.inv_mass[k],    p.fz[k] * p.inv_mass[k],
          p.tx[k] * p.inv_inertia[k], p.ty[k] * p.inv_inertia[k], p.tz[k] * p.inv_inertia[k]};
}

// The velocities the forces see, v + a kick (synchronised: v(t + dt) ~ v(t + dt/2) + a(t) dt/2),
// into k's kinematics block: step() and refresh_kinematics() both write them here, so a
// reorder predicts exactly what the step did.
void predict_velocities(const Particles& p, std::size_t k, const Accelerations& a, double kick,
                        double* kin) {
  kin[4] = p.vx[k] + a.ax * kick;
  kin[5] = p.vy[k] + a.ay * kick;
  kin[6] = p.vz[k] + a.az * kick;
  kin[8] = p.wx[k] + a.bx * kick;
  kin[9] = p.wy[k] + a.by * kick;
  kin[10] = p.wz[k] + a.bz * kick;
}

}  // namespace

double Engine::prediction_kick() const {
  return settings_.velocity_in_forces == VelocityInForces::kSynchronised ? 0.5 * settings_.dt_s
                                                                         : 0.0;
}

void Engine::refresh_kinematics(double kick) {
  const Particles& p = particles_;
  const std::size_t n = p.size();
  kin_.resize(kKinStride * n);  // every double written below, on the engine's threads
#pragma omp parallel for schedule(static) num_threads(settings_.threads)
  for (std::size_t k = 0; k < n; ++k) {
    double* kin = &kin_[kKinStride * k];
    kin[0] = p.x[k];
    kin[1] = p.y[k];
    kin[2] = p.z[k];
    kin[3] = p.radius[k];
    kin[7] = p.mass[k];
    kin[11] = 0.0;
    predict_velocities(p, k, accelerations(p, k), kick, kin);
  }
  index_wall_reach();
  index_pair_constants();
  choose_near_pairs(true);
}

void Engine::store_pair_springs() const {
  if (!pair_springs_stale_) return;
  near_.write_back(pairs_, settings_.threads);
  pair_springs_stale_ = false;
}

void Engine::choose_near_pairs(bool list_rebuilt) {
  // A ghost's moves are its owner's: the local drift's largest move does not bound them.
  if (halo_ != nullptr || !(settings_.near_margin > 0.0)) return;
  // The margin follows how fast the particles close gaps, counted in steps (so every thread
  // count chooses the same): a choice costs about a step (one test per listed pair; 2.8 ms of
  // the bed's 3.1 ms step at one thread), and pays where it lasts some tens of steps (the
  // settled bed: about 50 steps, 1.27x the whole list's step; a smaller margin took fewer pairs
  // but chose them too often). Chosen every few steps (a flowing hopper), the margin doubles,
  // and at the skin the whole list runs until the next rebuild, which tries again.
  constexpr std::uint64_t kFewSteps = 16, kManySteps = 64;
  if (near_.builds == 0) near_fraction_ = settings_.near_margin;
  if (!list_rebuilt) {
    const std::uint64_t lasted = step_ - near_built_at_;
    if (lasted < kFewSteps) near_fraction_ *= 2.0;
    if (lasted > kManySteps) near_fraction_ = std::max(near_fraction_ / 2.0, kMinNearFraction);
  }
  if (near_fraction_ >= 1.0) {  // as many pairs as the list: the list itself
    store_pair_springs();
    near_on_ = false;
    near_fraction_ = 0.5;  // what the next rebuild tries
    return;
  }
  near_on_ = true;
  near_built_at_ = step_;
  // Hot: a particle whose present speed alone would close the margin within kManySteps.
  const double margin = near_fraction_ * settings_.skin;
  near_.build(pairs_, list_rebuilt, kin_.data(), kKinStride, particles_.size(), margin,
              margin / (2.0 * static_cast<double>(kManySteps) * settings_.dt_s), settings_.threads);
}

void Engine::index_pair_constants() {
  // The same expressions the law used per pair and step, so nothing is rounded differently.
  const Particles& p = particles_;
  PairList& q = pairs_;
  const PairCoefficients& c = coefficients_;
  const std::size_t pairs = q.size();
  resize_to_overwrite(q.m_star, pairs);
  resize_to_overwrite(q.inv_kt, pairs);
#pragma omp parallel for schedule(static) num_threads(settings_.threads)
  for (std::size_t k = 0; k < pairs; ++k) {
    const double mi = p.mass[q.i[k]], mj = p.mass[q.j[k]];
    const double m_star = mi * mj / (mi + mj);
    q.m_star[k] = m_star;
    q.inv_kt[k] = detail::inverse_kt(c, m_star);
  }
}

void Engine::index_wall_reach() {
  // Until the next rebuild no particle moves more than skin/2 (the rebuild criterion), so a
  // particle farther than r + skin from a still wall's surface cannot touch it, and its spring
  // with it is zero (it was zeroed when their contact ended). Moving walls, walls past the
  // 32 bits and points with no closest surface point (outside a cylinder's axial extent) are
  // always checked.
  const Particles& p = particles_;
  const std::size_t n = p.size();
  wall_reach_.resize(n);
#pragma omp parallel for schedule(static) num_threads(settings_.threads)
  for (std::size_t k = 0; k < n; ++k) wall_reach_[k] = 0;
  for (std::size_t w = 0; w < settings_.walls.size() && w < 32; ++w) {
    const Wall& wall = settings_.walls[w];
    if (!wall.active(time_s_)) continue;
    const bool moving = wall.velocity != Vec3{0, 0, 0} && time_s_ < wall.move_until_s;
    const std::uint32_t bit = std::uint32_t{1} << w;
#pragma omp parallel for schedule(static) num_threads(settings_.threads)
    for (std::size_t k = 0; k < n; ++k) {
      Vec3 q;
      const double reach = p.radius[k] + settings_.skin;
      if (moving || !closest_point(wall, time_s_, {p.x[k], p.y[k], p.z[k]}, q) ||
          (p.x[k] - q[0]) * (p.x[k] - q[0]) + (p.y[k] - q[1]) * (p.y[k] - q[1]) +
                  (p.z[k] - q[2]) * (p.z[k] - q[2]) <
              reach * reach) {
        wall_reach_[k] |= bit;
      }
    }
  }
  // The particles some wall may reach, in order (all of them past 32 walls): the finish visits
  // only these, a few per cent of a bed's or a hopper's particles.
  // Listed by each thread for its range, in order: no serial pass over the particles.
  const bool all = settings_.walls.size() > 32;
  count_then_fill(
      n, settings_.threads,
      [&](std::size_t first, std::size_t last) {
        std::size_t mine = 0;
        for (std::size_t k = first; k < last; ++k) mine += all || wall_reach_[k] != 0;
        return mine;
      },
      [&](std::size_t total) { wall_reachers_.resize(total); },
      [&](std::size_t first, std::size_t last, std::size_t at) {
        for (std::size_t k = first; k < last; ++k) {
          if (all || wall_reach_[k] != 0) wall_reachers_[at++] = static_cast<std::uint32_t>(k);
        }
      });
}

void Engine::store_forces() {
  if (!forces_in_sums_) return;
  forces_in_sums_ = false;
  Particles& p = particles_;
  const double* acc = acc_.data();
  const std::size_t n = p.size();
#pragma omp parallel for schedule(static) num_threads(settings_.threads)
  for (std::size_t a = 0; a < n; ++a) {
    const double* s = acc + kAccStride * a;
    p.fx[a] = s[0];
    p.fy[a] = s[1];
    p.fz[a] = s[2];
    p.tx[a] = s[3];
    p.ty[a] = s[4];
    p.tz[a] = s[5];
    p.contacts[a] = static_cast<std::uint16_t>(s[6]);
    p.force_magnitude[a] = s[7];
  }
}

void Engine::rebuild() {
  store_forces();        // the sink, the migrants, the reorder and the velocities below read them
  store_pair_springs();  // what the new list carries
  // With a halo: the ghosts leave before the sink (it counts owned particles only), and the
  // migrants and new ghosts arrive after it, their springs carried along.
  if (halo_ != nullptr) halo_->drop_ghosts(particles_, pairs_, carried_);
  // sink.cpp: removals happen at rebuilds only; they renumber the particles, so the springs
  // then go by stable ids (carried_).
  const bool removed = remove_sunk_particles();
  check_containment();  // this process's own particles, once the sink has taken its
  if (halo_ != nullptr) {
    halo_->exchange_particles(particles_, carried_);
    builder_.rebuild(particles_, pairs_, settings_.domain, settings_.skin, settings_.threads, halo_,
                     &carried_);
  } else if (!particles_.id.empty()) {
    builder_.rebuild(particles_, pairs_, settings_.domain, settings_.skin, settings_.threads,
                     nullptr, removed ? &carried_ : nullptr);
  }
  ++rebuilds_;
  index_ids();
  run_particles_ = particles_.size();
  if (halo_ != nullptr) {
    halo_->index_ghosts(particles_);
    run_particles_ = static_cast<std::uint64_t>(
        std::llround(halo_->sum_over_ranks(static_cast<double>(halo_->owned_count()))));
  }
  refresh_kinematics(prediction_kick());
}

void Engine::check_containment() const {
  if (!settings_.domain_bounds_particles) return;
  const Particles& p = particles_;
  const Domain& d = settings_.domain;
  const AlignedVector<double>* axes[3] = {&p.x, &p.y, &p.z};
  const auto n = static_cast<std::int64_t>(p.size());
  std::int64_t first = n;
#pragma omp parallel for num_threads(settings_.threads) reduction(min : first) schedule(static)
  for (std::int64_t a = 0; a < n; ++a) {
    for (int axis = 0; axis < 3; ++axis) {
      const double c = (*axes[axis])[static_cast<std::size_t>(a)], margin = d.length(axis);
      if (!d.periodic[axis] && !(c >= d.lo[axis] - margin && c <= d.hi[axis] + margin)) {
        first = std::min(first, a);
      }
    }
  }
  if (first == n) return;
  const std::string what = fmt::format(
      "more than a box length outside the domain [{:.6g}, {:.6g}] x [{:.6g}, {:.6g}] x [{:.6g}, "
      "{:.6g}] m",
      d.lo[0], d.hi[0], d.lo[1], d.hi[1], d.lo[2], d.hi[2]);
  const auto a = static_cast<std::size_t>(first);
  if (rebuilds_ == 0) {  // the constructor's build: the input put it there
    throw InputError(fmt::format("particle {} starts at ({:.9g}, {:.9g}, {:.9g}) m, {}", p.id[a],
                                 p.x[a], p.y[a], p.z[a], what));
  }
  fail("flung " + what + " (a wall missing, or the box too small: widen \"domain\")",
       static_cast<std::uint32_t>(a));
}

void Engine::fail(const std::string& what, std::uint32_t index) const {
  const Particles& p = particles_;
  throw UnstableRun(
      fmt::format("{} at step {} (t = {:.9g} s): particle {} at ({:.9g}, {:.9g}, "
                  "{:.9g}) m",
                  what, step_, time_s_, p.id[index], p.x[index], p.y[index], p.z[index]));
}

void Engine::step() { advance(false); }

std::uint64_t Engine::run_steps(std::uint64_t steps, BatchEnd end) {
  const bool at_rebuild = end == BatchEnd::kAtRebuild;
  std::uint64_t done = 0;
  while (done < steps) {
    if (done > 0 && run_particles_ == 0) break;  // the sink took every particle
    // A finish drifts the next step only where no ghost is exchanged in between.
    const bool rebuilt =
        advance(done + 1 < steps && (halo_ == nullptr || !halo_->exchanges_ghosts()), at_rebuild);
    ++done;
    if (rebuilt && at_rebuild) break;
  }
  return done;
}

bool Engine::advance(bool drift_next, bool end_at_rebuild) {
  Particles& p = particles_;
  const std::size_t n = p.size();
  const double dt = settings_.dt_s;
  const double move_limit_sq = 0.25 * settings_.skin * settings_.skin;  // (skin/2)^2
  double t0 = omp_get_wtime();
  double max_disp_sq = 0.0, max_step_sq = 0.0;
  std::uint32_t bad = UINT32_MAX;  // the first particle that moved too far or is not finite
  particle_steps_ += halo_ != nullptr ? halo_->owned_count() : n;
  if (drifted_) {  // the last finish drifted this step already
    drifted_ = false;
    max_disp_sq = drifted_disp_sq_;
    max_step_sq = drifted_step_sq_;
    bad = drifted_bad_;
  } else {
    store_forces();
    static constexpr std::array kDrifts{&Engine::drift_on<StepIsa::kBaseline>,
                                        &Engine::drift_on<StepIsa::kAvx2>,
                                        &Engine::drift_on<StepIsa::kAvx512>};
    (this->*kDrifts[static_cast<std::size_t>(step_isa_)])(max_disp_sq, max_step_sq, bad);
  }
  // Time from the last (re)start's base: exact multiples of dt, also after a dt change.
  time_s_ = base_time_s_ + static_cast<double>(step_ + 1 - base_step_) * dt;
  ++step_;
  double t1 = omp_get_wtime();
  phases_.integrate_s += t1 - t0;
  if (bad != UINT32_MAX) {
    store_forces();  // the run ends here: what it leaves shows the last forces
    const double m = std::hypot(p.vx[bad], p.vy[bad], p.vz[bad]) * dt;
    fail(std::isfinite(m) ? fmt::format("moved {:.3g} m in one step, more than skin/2 = {:.3g} m",
                                        m, 0.5 * settings_.skin)
                          : std::string("position or velocity is not finite (NaN)"),
         bad);
  }
  // Every process rebuilds at the same step: the largest move over all of them decides.
  if (halo_ != nullptr) max_disp_sq = halo_->max_over_ranks(max_disp_sq);
  const bool rebuilds = max_disp_sq > move_limit_sq;
  if (rebuilds) {
    rebuild();
    phases_.neighbor_s += omp_get_wtime() - t1;
  } else if (near_on_) {
    near_.moved += std::sqrt(max_step_sq);
    if (near_.stale()) {
      choose_near_pairs(false);
      phases_.neighbor_s += omp_get_wtime() - t1;
    }
  }
  // The finish can drift a particle only once every pair that reads its kinematics block is
  // done: after the pass (update=separate), or among the ordered pass's rows (update=fused: a
  // particle is finished once no later row reaches it, and no row reads it after that), not among
  // the full list's blocks (another thread's block may still read any particle's).
  const ForceVariant& variant = settings_.force_variant;
  compute_forces(true,
                 drift_next && !(rebuilds && end_at_rebuild) &&
                     !(variant.fused_update && variant.accumulation != Accumulation::kOrdered));
  return rebuilds;
}

void Engine::check_pair_overlap(std::size_t k) const {
  const Particles& p = particles_;
  const PairList& q = force_pairs();
  const std::uint32_t i = q.i[k], j = q.j[k];
  const auto& sh = q.shift[q.image[k]];
  const double overlap =
      p.radius[i] + p.radius[j] -
      std::hypot(p.x[i] - p.x[j] - sh[0], p.y[i] - p.y[j] - sh[1], p.z[i] - p.z[j] - sh[2]);
  fail(fmt::format("overlap {:.3g} m with particle {} is above 10 % of the smaller diameter",
                   overlap, p.id[j]),
       i);
}

void Engine::set_force_variant(const ForceVariant& variant) {
  if (const auto rule = broken_rule(variant)) {
    throw InputError("force variant '" + to_string(variant) + "': " + std::string(*rule));
  }
  settings_.force_variant = variant;
}

// The step's hot loops on the instruction set the engine was made for (engine_isa.cpp).
void Engine::compute_forces(bool final_kick, bool drift_next) {
  static constexpr std::array kPasses{&Engine::compute_forces_on<StepIsa::kBaseline>,
                                      &Engine::compute_forces_on<StepIsa::kAvx2>,
                                      &Engine::compute_forces_on<StepIsa::kAvx512>};
  const std::uint64_t large_before = large_overlaps_;
  (this->*kPasses[static_cast<std::size_t>(step_isa_)])(final_kick, drift_next);
  if (halo_ != nullptr) halo_->refresh_ghosts(particles_);
  const std::uint64_t large = large_overlaps_ - large_before;
  if (large > 0 && !warned_ && settings_.warn_large_overlaps) {
    warned_ = true;
    fmt::print(stderr,
               "contactlab dem: warning: {} contacts overlap by more than 1 % of the smaller "
               "diameter at step {} (warned once; the run's count is in the summary)\n",
               large, step_);
  }
}

}  // namespace contactlab::dem
