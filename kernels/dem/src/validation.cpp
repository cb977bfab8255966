// Validation rows, the case registry and the normal-impact experiment shared with the
// time-step study.
#include "contactlab/dem/validation.hpp"

#include <cmath>

namespace contactlab::dem {

namespace {
EngineSettings& validation_defaults() {
  static EngineSettings settings;
  return settings;
}
}  // namespace

void set_validation_engine(const ForceVariant& variant, int threads) {
  validation_defaults().force_variant = variant;
  validation_defaults().threads = threads;
}

EngineSettings validation_engine() { return validation_defaults(); }

ValidationRow make_row(std::string case_name, std::string quantity, double expected,
                       double measured, double tolerance, bool relative, std::string note) {
  ValidationRow row;
  row.case_name = std::move(case_name);
  row.quantity = std::move(quantity);
  row.expected = expected;
  row.measured = measured;
  row.error = std::abs(measured - expected) / (relative ? std::abs(expected) : 1.0);
  row.tolerance = tolerance;
  row.relative = relative;
  row.pass = row.error <= tolerance;  // false for NaN
  row.note = std::move(note);
  return row;
}

ImpactResult run_normal_impact(const ContactLaw& law, double r1, double r2, double density,
                               double v0, double dt_s, VelocityInForces velocity, double phase) {
  EngineSettings s = validation_engine();
  s.warn_large_overlaps = false;
  s.law = law;
  s.dt_s = dt_s;
  s.velocity_in_forces = velocity;
  s.domain.lo = {-1, -1, -1};
  s.domain.hi = {1, 1, 1};
  Particles p;
  const double gap =
      0.05 * r1 + phase * v0 * dt_s;  // just apart: the first touch is inside the skin
  if (r2 > 0) {
    p.add(0, 0, -(r1 + 0.5 * gap), 0, 0, r1, density);
    p.add(1, 0, r2 + 0.5 * gap, 0, 0, r2, density);
    // Equal and opposite momenta: the centre of mass rests.
    const double m1 = p.mass[0], m2 = p.mass[1];
    p.vx[0] = v0 * m2 / (m1 + m2);
    p.vx[1] = -v0 * m1 / (m1 + m2);
  } else {
    Wall floor;
    floor.name = "floor";
    floor.point = {0, 0, 0};
    floor.normal = {1, 0, 0};
    s.walls.push_back(floor);
    p.add(0, 0, r1 + gap, 0, 0, r1, density);
    p.vx[0] = -v0;
  }
  ImpactResult result;
  result.m_star = r2 > 0 ? p.mass[0] * p.mass[1] / (p.mass[0] + p.mass[1]) : p.mass[0];
  Engine engine(s, std::move(p));
  auto relative_velocity = [&] {
    const Particles& q = engine.particles();
    if (r2 > 0) return q.vx[engine.index_of(1)] - q.vx[engine.index_of(0)];
    return -q.vx[0];
  };
  const double before = relative_velocity();  // closing speed, > 0
  std::uint64_t touching_steps = 0;
  bool started = false;
  for (std::uint64_t step = 0; step < 10'000'000; ++step) {
    engine.step();
    const bool touching = engine.particles().force_magnitude[engine.index_of(0)] > 0;
    touching_steps += touching;
    started = started || touching;
    if (started && !touching) break;
  }
  result.restitution = -relative_velocity() / before;
  result.contact_time_s = static_cast<double>(touching_steps) * dt_s;
  return result;
}

double mean_restitution(const ContactLaw& law, double r1, double r2, double density, double v0,
                        double dt_s, VelocityInForces velocity, int phases) {
  double sum = 0.0;
  for (int k = 0; k < phases; ++k) {
    sum +=
        run_normal_impact(law, r1, r2, density, v0, dt_s, velocity, (k + 0.5) / phases).restitution;
  }
  return sum / phases;
}

}  // namespace contactlab::dem
