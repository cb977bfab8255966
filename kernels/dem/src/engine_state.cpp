// The engine's state as a whole: its energy balance, and the restore from a checkpoint.
#include <cmath>
#include <stdexcept>

#include "contactlab/dem/engine.hpp"

namespace contactlab::dem {

Energies Engine::energies() const {
  Energies e = local_energies();
  double initial = initial_energy_;
  if (halo_ != nullptr) {  // each process's initial energy less what its sink took
    e.kinetic = halo_->sum_over_ranks(e.kinetic);
    e.potential = halo_->sum_over_ranks(e.potential);
    initial = halo_->sum_over_ranks(initial);
  }
  e.dissipated = initial - (e.kinetic + e.potential);
  return e;
}

Snapshot Engine::snapshot() const {
  if (halo_ != nullptr) throw std::logic_error("Engine::snapshot of one process's part of a run");
  return {particles_, settings_, time_s_, step_, energies(), removed_count_, removed_mass_};
}

Energies Engine::local_energies() const {
  const Particles& p = particles_;
  const PairCoefficients& c = coefficients_;
  Energies e;
  double elastic = 0.0;
  for (std::size_t a = 0; a < p.size(); ++a) {
    if (halo_ != nullptr && halo_->is_ghost(a)) continue;  // its owner counts it
    e.kinetic += 0.5 * p.mass[a] * (p.vx[a] * p.vx[a] + p.vy[a] * p.vy[a] + p.vz[a] * p.vz[a]);
    e.kinetic +=
        0.5 / p.inv_inertia[a] * (p.wx[a] * p.wx[a] + p.wy[a] * p.wy[a] + p.wz[a] * p.wz[a]);
    e.potential -= p.mass[a] * (settings_.gravity[0] * p.x[a] + settings_.gravity[1] * p.y[a] +
                                settings_.gravity[2] * p.z[a]);
    for (std::size_t w = 0; w < settings_.walls.size(); ++w) {
      Vec3 cp;
      if (!closest_point(settings_.walls[w], time_s_, {p.x[a], p.y[a], p.z[a]}, cp)) continue;
      const double delta = p.radius[a] - std::hypot(p.x[a] - cp[0], p.y[a] - cp[1], p.z[a] - cp[2]);
      if (delta <= 0) continue;
      const double kn = c.k_n(p.mass[a]);
      const double h2 = p.wall_spring[3 * w][a] * p.wall_spring[3 * w][a] +
                        p.wall_spring[3 * w + 1][a] * p.wall_spring[3 * w + 1][a] +
                        p.wall_spring[3 * w + 2][a] * p.wall_spring[3 * w + 2][a];
      elastic += 0.5 * kn * delta * delta + 0.5 * c.kt_ratio * kn * h2;
    }
  }
  const PairList& q = force_pairs();  // every touching pair
  for (std::size_t k = 0; k < q.size(); ++k) {
    const std::uint32_t i = q.i[k], j = q.j[k];
    const auto& sh = q.shift[q.image[k]];
    const double delta =
        p.radius[i] + p.radius[j] -
        std::hypot(p.x[i] - p.x[j] - sh[0], p.y[i] - p.y[j] - sh[1], p.z[i] - p.z[j] - sh[2]);
    if (delta <= 0) continue;
    const double kn = c.k_n(q.m_star[k]);
    const double h2 = q.hx[k] * q.hx[k] + q.hy[k] * q.hy[k] + q.hz[k] * q.hz[k];
    // With a halo, a pair is every process's that holds one of its particles: each counts its
    // own particles' halves.
    const double share =
        halo_ == nullptr
            ? 1.0
            : 0.5 * ((halo_->is_ghost(i) ? 0.0 : 1.0) + (halo_->is_ghost(j) ? 0.0 : 1.0));
    elastic += share * (0.5 * kn * delta * delta + 0.5 * c.kt_ratio * kn * h2);
  }
  e.potential += elastic;
  return e;
}

void Engine::set_counters(const State& state) {
  drifted_ = false;  // restored whole: no step is half done
  time_s_ = state.time_s;
  // The run's time base where it gives the state's time with this dt (the run goes on as it
  // would have); otherwise (dt changed, or a state without one) the time restarts from here.
  const bool base_holds =
      state.base_step <= state.step &&
      state.base_time_s + static_cast<double>(state.step - state.base_step) * settings_.dt_s ==
          state.time_s;
  base_time_s_ = base_holds ? state.base_time_s : state.time_s;
  base_step_ = base_holds ? state.base_step : state.step;
  step_ = state.step;
  rebuilds_ = state.rebuilds;
  large_overlaps_ = state.large_overlaps;
  initial_energy_ = state.initial_energy;
  removed_count_ = state.removed_count;
  removed_mass_ = state.removed_mass;
}

void Engine::restore(const State& state, Particles particles, PairList pairs) {
  set_counters(state);
  particles_ = std::move(particles);
  const auto shift = pairs_.shift;
  pair_springs_stale_ = false;  // the saved springs are the ones
  pairs_ = std::move(pairs);
  pairs_.shift = shift;
  pairs_.resize(pairs_.i.size());
  pairs_.build_csr(particles_.size());
  index_ids();
  // (the next step predicts every velocity again before it computes forces)
  refresh_kinematics(prediction_kick());
}

}  // namespace contactlab::dem
