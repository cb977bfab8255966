// Speed against error over the time step: for dt = t_c/10 ... t_c/200, the wall time per
// simulated second of a scene and the errors of a two-body impact in e and in energy.
#pragma once

#include <cstdint>
#include <vector>

#include "contactlab/dem/engine.hpp"

namespace contactlab::dem {

struct TimestepRow {
  double divisor = 0.0;  // dt = t_c / divisor
  double dt_s = 0.0;
  double wall_per_simulated_s = 0.0;  // s of wall time per s simulated (the scene); < 0: unstable
  double e_error_synchronised = 0.0;  // |e - e_predicted| (clamp-predicted), synchronised v
  double e_error_half_step = 0.0;     // the same with half-step velocities in the dashpot
  double energy_error = 0.0;          // |1 - e^2| of the same impact with e = 1 (elastic)
};

struct TimestepStudy {
  double contact_time_s = 0.0;  // t_c of the lightest pair
  double stable_dt_s = 0.0;
  double recommended_dt_s = 0.0;  // t_c / 50
  std::vector<TimestepRow> rows;
};

// `settings` and `particles` make the timed scene (run `steps` steps per dt); the impacts use
// settings.law on two spheres of the smallest radius and the lightest particles' density.
TimestepStudy timestep_study(const EngineSettings& settings, const Particles& particles,
                             std::uint64_t steps,
                             const std::vector<double>& divisors = {10, 20, 50, 100, 200});

}  // namespace contactlab::dem
