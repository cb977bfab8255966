// The DEM validation cases (analytic laws the engine must reproduce) as named, runnable cases
// with their expected and measured figures; `contactlab dem validate` and the CTests run them.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "contactlab/dem/engine.hpp"

namespace contactlab::dem {

// One checked figure. `error` is relative (|measured - expected| / |expected|) when
// `relative`, else absolute; it passes when error <= tolerance.
struct ValidationRow {
  std::string case_name;
  std::string quantity;
  double expected = 0.0;
  double measured = 0.0;
  double error = 0.0;
  double tolerance = 0.0;
  bool relative = true;
  bool pass = false;
  std::string note;  // what the expected value is (e.g. "clamp-predicted")
};

ValidationRow make_row(std::string case_name, std::string quantity, double expected,
                       double measured, double tolerance, bool relative, std::string note = "");

struct ValidationCase {
  std::string name;
  std::string description;
  std::function<std::vector<ValidationRow>()> run;
};

// Every case, in the order `dem validate` prints them.
const std::vector<ValidationCase>& validation_cases();

// The engine settings every case starts from: defaults, except the force variant and thread
// count chosen here (`dem validate --variant V --threads T` runs every case on that variant).
// Process-wide; set it before running cases, not while they run.
void set_validation_engine(const ForceVariant& variant, int threads);
EngineSettings validation_engine();

// A two-body head-on impact (sphere-sphere of radii r1, r2, or a sphere on a plane wall when
// r2 = 0) at relative speed v0: the measured restitution and normal-force duration. `phase`
// in [0, 1) shifts the first touch within a step (the dashpot force jumps on at the first
// touch, an O(dt) error that depends on this phase; averaging over phases isolates the
// systematic bias of the velocity fed to the dashpot).
struct ImpactResult {
  double restitution = 0.0;
  double contact_time_s = 0.0;
  double m_star = 0.0;
};
ImpactResult run_normal_impact(const ContactLaw& law, double r1, double r2, double density,
                               double v0, double dt_s, VelocityInForces velocity,
                               double phase = 0.0);

// The mean restitution over `phases` evenly spaced first-touch phases.
double mean_restitution(const ContactLaw& law, double r1, double r2, double density, double v0,
                        double dt_s, VelocityInForces velocity, int phases = 16);

}  // namespace contactlab::dem
