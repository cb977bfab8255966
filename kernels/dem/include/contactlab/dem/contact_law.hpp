// The DEM contact law: linear spring-dashpot normal force, linear history spring with Coulomb
// friction, optional constant rolling resistance; its pair coefficients and closed-form
// predictions (restitution with the clamped force, contact time, stable time step).
#pragma once

namespace contactlab::dem {

// How the normal law is given. kRestitution: every pair has the same (e, t_c) whatever its
// reduced mass m*, so k_n = m* (pi^2 + ln^2 e) / t_c^2 and the dashpot c_n = -2 m* ln e / t_c
// (polydisperse pairs keep the set e). kStiffness: k_n [N/m] and gamma_n [1/s] per unit reduced
// mass as in LAMMPS gran/hooke/history (c_n = m* gamma_n), so e and t_c depend on m*.
enum class NormalLawKind { kRestitution, kStiffness };

struct ContactLaw {
  NormalLawKind kind = NormalLawKind::kRestitution;
  double restitution = 0.5;       // e in (0, 1]
  double contact_time_s = 1e-4;   // t_c of the undamped-clamp formula
  double normal_stiffness = 0.0;  // k_n [N/m], kStiffness only
  double normal_damping = 0.0;    // gamma_n [1/s] per unit reduced mass, kStiffness only
  double friction = 0.5;          // Coulomb mu >= 0
  double tangential_stiffness_ratio = 2.0 / 7.0;  // k_t / k_n (LAMMPS default 2/7)
  double tangential_damping_ratio = 0.5;          // gamma_t / gamma_n (LAMMPS default 1/2)
  double rolling_friction = 0.0;                  // mu_r; 0 = off (constant-torque model)
  // F_n = max(0, k_n delta - c_n v_n): no attraction at the end of a damped contact (LAMMPS
  // limit_damping). It raises the measured e above exp(-beta t_c): see predict_impact().
  bool clamp_normal_force = true;
};

// k_n(m*) = k_abs + k_per_mass m*, c_n(m*) = c_per_mass m*: one form for both kinds, so the
// force loop needs only m* per pair and no branch.
struct PairCoefficients {
  double k_abs = 0.0;       // N/m
  double k_per_mass = 0.0;  // N/m per kg
  double c_per_mass = 0.0;  // 1/s (damping coefficient per kg of reduced mass)
  double kt_ratio = 2.0 / 7.0;
  double ct_ratio = 0.5;
  double mu = 0.0;
  double mu_roll = 0.0;
  bool clamp = true;
  double k_n(double m_star) const { return k_abs + k_per_mass * m_star; }
  double c_n(double m_star) const { return c_per_mass * m_star; }
};

PairCoefficients pair_coefficients(const ContactLaw& law);

// Two-body normal impact of reduced mass m* (a wall: m* = the particle's mass) with the damped
// linear oscillator x'' + 2 beta x' + w0^2 x = 0 (Schwager & Poeschel 2007).
struct ImpactPrediction {
  double restitution = 0.0;     // the velocity ratio after/before
  double contact_time_s = 0.0;  // the time the normal force acts
};

// Without the clamp: e = exp(-beta t_c), t_c = pi / sqrt(w0^2 - beta^2). With it the force
// vanishes where x'' = 0, at w t* = pi - atan(2 beta w / (w^2 - beta^2)) (w = sqrt(w0^2 -
// beta^2)), and e = exp(-beta t*) (beta sin w t* - w cos w t*) / w > exp(-beta t_c).
ImpactPrediction predict_impact(const PairCoefficients& law, double m_star);

// Largest stable velocity-Verlet step for the stiffest pair (smallest reduced mass):
// dt < (2 / w0) (sqrt(1 + zeta^2) - zeta), zeta = beta / w0 (undamped: 2 / w0 = 0.64 t_c).
double stable_time_step(const PairCoefficients& law, double smallest_m_star);

// t_c of the pair of smallest reduced mass (for the recommended dt = t_c / 50).
double contact_time(const PairCoefficients& law, double m_star);

}  // namespace contactlab::dem
