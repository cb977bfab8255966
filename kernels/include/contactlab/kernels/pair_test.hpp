// The contact test of Takagi et al. eq. (2), shared by every kernel and the brute force so that
// all of them round identically: touching (distance exactly D) counts as contact.
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>

namespace contactlab {

// Equal diameters D: D^2 >= dx^2 + dy^2 + dz^2, with reach_sq = D * D. Real is double, or
// float for the single-precision variants.
template <class Real>
inline bool in_contact(Real dx, Real dy, Real dz, Real reach_sq) {
  return dx * dx + dy * dy + dz * dz <= reach_sq;
}

// Diameters d_i, d_j: (d_i + d_j)^2 >= 4 r^2 (eq. (1) squared; the factor 4 is exact).
template <class Real>
inline bool in_contact(Real dx, Real dy, Real dz, Real d_i, Real d_j) {
  const Real sum = d_i + d_j;
  return Real(4) * (dx * dx + dy * dy + dz * dz) <= sum * sum;
}

// Single precision with the double test's answers. The float test decides where its rounding
// cannot change the answer; the few pairs within a rounding band of touching are tested again
// in double (the cost of the rare second test instead of wrong contacts). The band bounds the
// float result's distance from the double one for every candidate of a 27-cell stencil:
// coordinates relative to the box corner of magnitude at most `extent`, per-axis offsets under
// `offset` (two cell widths), diameters at most `diameter`.
struct FloatBand {
  float sure = 0, unsure = 0;  // equal diameters: contact if s <= sure, none if s > unsure
  float margin = 0;  // per-particle diameters: contact if t >= margin, none if t < -margin

  // reach_sq: D^2 as the double test has it (unused with per-particle diameters).
  static FloatBand make(double extent, double offset, double diameter, double reach_sq) {
    constexpr double u = 0x1.0p-24;  // float's unit roundoff (double's is negligible beside it)
    // A coordinate difference: both coordinates and the difference rounded.
    const double e = u * (2.001 * extent + 1.001 * offset);
    const double w = offset + e;
    // The sum of squares: three differences squared (e (2 offset + e) each), rounded squares
    // and two roundings of the sum; doubled for the second-order terms and double's rounding.
    const double squares = 2.0 * (3.0 * e * (2.0 * offset + e) + 9.0 * u * w * w);
    // With diameters: t = (d_i + d_j)^2 - 4 s, the diameters, their sum, its square and t
    // rounded besides.
    const double t_error = 4.0 * squares + 2.0 * (20.0 * u * diameter * diameter) +
                           2.0 * u * (4.0 * diameter * diameter + 12.0 * w * w);
    constexpr float inf = std::numeric_limits<float>::infinity();
    FloatBand band;
    band.sure = std::nextafter(static_cast<float>(reach_sq - squares), -inf);
    band.unsure = std::nextafter(static_cast<float>(reach_sq + squares), inf);
    band.margin = std::nextafter(static_cast<float>(2.0 * t_error), inf);
    return band;
  }
};

// The double coordinates (and diameters) in the working order: the second test of the float
// pairs within FloatBand of touching, which gives the double test's answer.
struct ExactCoordinates {
  const double *x, *y, *z, *d;
  double reach_sq;  // D^2 in double (without per-particle diameters)

  bool in_contact(std::uint32_t h, std::uint32_t j, bool diameters) const {
    const double dx = x[h] - x[j], dy = y[h] - y[j], dz = z[h] - z[j];
    return diameters ? contactlab::in_contact(dx, dy, dz, d[h], d[j])
                     : contactlab::in_contact(dx, dy, dz, reach_sq);
  }
};

// The float decision of a candidate at squared distance s (sum: d_i + d_j in float, with
// per-particle diameters): contact, or within the band (unsure: the double test decides).
template <bool kDiameters>
inline bool float_contact(float s, float sum, const FloatBand& band, bool& unsure) {
  if constexpr (kDiameters) {
    const float t = sum * sum - 4.0f * s;
    unsure = (t < band.margin) & (t >= -band.margin);
    return t >= band.margin;
  } else {
    unsure = (s > band.sure) & (s <= band.unsure);
    return s <= band.sure;
  }
}

}  // namespace contactlab
