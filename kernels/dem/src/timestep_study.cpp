// The time-step table: scene timings and two-body impact errors per dt.
#include "contactlab/dem/timestep_study.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "contactlab/dem/validation.hpp"

namespace contactlab::dem {

TimestepStudy timestep_study(const EngineSettings& settings, const Particles& particles,
                             std::uint64_t steps, const std::vector<double>& divisors) {
  TimestepStudy study;
  const PairCoefficients c = pair_coefficients(settings.law);
  std::size_t lightest = 0;
  for (std::size_t k = 0; k < particles.size(); ++k) {
    if (particles.mass[k] < particles.mass[lightest]) lightest = k;
  }
  const double m = particles.mass[lightest], r = particles.radius[lightest];
  const double density = m / (4.0 / 3.0 * std::numbers::pi * r * r * r);
  study.contact_time_s = contact_time(c, 0.5 * m);
  study.stable_dt_s = stable_time_step(c, 0.5 * m);
  if (!settings.walls.empty())
    study.stable_dt_s = std::min(study.stable_dt_s, stable_time_step(c, m));
  study.recommended_dt_s = study.contact_time_s / 50;
  ContactLaw elastic = settings.law;
  elastic.friction = 0.0;
  if (elastic.kind == NormalLawKind::kRestitution) {
    elastic.restitution = 1.0;
  } else {
    elastic.normal_damping = 0.0;
  }
  ContactLaw frictionless = settings.law;
  frictionless.friction = 0.0;
  for (const double divisor : divisors) {
    TimestepRow row;
    row.divisor = divisor;
    row.dt_s = study.contact_time_s / divisor;
    const double v0 = 0.1;  // m/s: small against any move limit
    const ImpactPrediction want = predict_impact(pair_coefficients(frictionless), 0.5 * m);
    row.e_error_synchronised = std::abs(mean_restitution(frictionless, r, r, density, v0, row.dt_s,
                                                         VelocityInForces::kSynchronised) -
                                        want.restitution);
    row.e_error_half_step = std::abs(
        mean_restitution(frictionless, r, r, density, v0, row.dt_s, VelocityInForces::kHalfStep) -
        want.restitution);
    const double e1 =
        mean_restitution(elastic, r, r, density, v0, row.dt_s, VelocityInForces::kSynchronised);
    row.energy_error = std::abs(1.0 - e1 * e1);
    if (steps > 0) {
      EngineSettings s = settings;
      s.dt_s = row.dt_s;
      try {
        Engine engine(s, particles);
        const double t0 = omp_get_wtime();
        engine.run_steps(steps);
        row.wall_per_simulated_s = (omp_get_wtime() - t0) / (static_cast<double>(steps) * s.dt_s);
      } catch (const std::exception&) {
        row.wall_per_simulated_s = -1.0;  // refused or unstable at this dt
      }
    }
    study.rows.push_back(row);
  }
  return study;
}

}  // namespace contactlab::dem
