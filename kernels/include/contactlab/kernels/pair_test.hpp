// The contact test of Takagi et al. eq. (2), shared by every kernel and the brute force so that
// all of them round identically: touching (distance exactly D) counts as contact.
#pragma once

namespace contactlab {

// Equal diameters D: D^2 >= dx^2 + dy^2 + dz^2, with reach_sq = D * D.
inline bool in_contact(double dx, double dy, double dz, double reach_sq) {
  return dx * dx + dy * dy + dz * dz <= reach_sq;
}

// Diameters d_i, d_j: (d_i + d_j)^2 >= 4 r^2 (eq. (1) squared; the factor 4 is exact).
inline bool in_contact(double dx, double dy, double dz, double d_i, double d_j) {
  const double sum = d_i + d_j;
  return 4.0 * (dx * dx + dy * dy + dz * dz) <= sum * sum;
}

}  // namespace contactlab
