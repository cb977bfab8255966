// The contact test of Takagi et al. eq. (2), shared by every kernel and the brute force so that
// all of them round identically: touching (distance exactly D) counts as contact.
#pragma once

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

}  // namespace contactlab
