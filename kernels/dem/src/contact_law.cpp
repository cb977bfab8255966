// Pair coefficients and closed-form predictions of the linear spring-dashpot law.
#include "contactlab/dem/contact_law.hpp"

#include <cmath>
#include <numbers>

namespace contactlab::dem {

PairCoefficients pair_coefficients(const ContactLaw& law) {
  PairCoefficients c;
  if (law.kind == NormalLawKind::kRestitution) {
    const double ln_e = std::log(law.restitution);
    const double tc = law.contact_time_s;
    c.k_per_mass = (std::numbers::pi * std::numbers::pi + ln_e * ln_e) / (tc * tc);
    c.c_per_mass = -2.0 * ln_e / tc;
  } else {
    c.k_abs = law.normal_stiffness;
    c.c_per_mass = law.normal_damping;
  }
  c.kt_ratio = law.tangential_stiffness_ratio;
  c.ct_ratio = law.tangential_damping_ratio;
  c.mu = law.friction;
  c.mu_roll = law.rolling_friction;
  c.clamp = law.clamp_normal_force;
  return c;
}

ImpactPrediction predict_impact(const PairCoefficients& law, double m_star) {
  const double w0_sq = law.k_n(m_star) / m_star;
  const double beta = 0.5 * law.c_n(m_star) / m_star;
  const double w = std::sqrt(w0_sq - beta * beta);
  ImpactPrediction p;
  if (!law.clamp) {
    p.contact_time_s = std::numbers::pi / w;
    p.restitution = std::exp(-beta * p.contact_time_s);
    return p;
  }
  // x(t) = (v0 / w) exp(-beta t) sin(w t); the force k x + c x' = -m* x'' vanishes at x'' = 0.
  const double phase = std::numbers::pi - std::atan2(2.0 * beta * w, w * w - beta * beta);
  const double t_star = phase / w;
  p.contact_time_s = t_star;
  p.restitution = std::exp(-beta * t_star) * (beta * std::sin(phase) - w * std::cos(phase)) / w;
  return p;
}

double stable_time_step(const PairCoefficients& law, double smallest_m_star) {
  const double w0 = std::sqrt(law.k_n(smallest_m_star) / smallest_m_star);
  const double zeta = 0.5 * law.c_n(smallest_m_star) / smallest_m_star / w0;
  return 2.0 / w0 * (std::sqrt(1.0 + zeta * zeta) - zeta);
}

double contact_time(const PairCoefficients& law, double m_star) {
  const double w0_sq = law.k_n(m_star) / m_star;
  const double beta = 0.5 * law.c_n(m_star) / m_star;
  return std::numbers::pi / std::sqrt(w0_sq - beta * beta);
}

}  // namespace contactlab::dem
