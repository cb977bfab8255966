// pair_test.hpp's FloatBand: wherever the float test decides (not unsure), it decides as the
// double test does, for boxes near and far from the origin, small and large D, with and without
// per-particle diameters; and the band is narrow (few candidates are unsure).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "contactlab/kernels/pair_test.hpp"

namespace contactlab {
namespace {

struct Case {
  double lo, extent, d;  // box corner (each axis), its extent, the contact distance
};

// Pairs at distances spread over [0, 2 offset] and piled up within 1e-5 of d: the float
// decision where it is sure against the double one, counting the unsure ones.
void check_band(const Case& c, bool diameters) {
  std::mt19937_64 rng(12345);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double offset = 2.0 * c.d;  // two cells of width d
  const double reach_sq = c.d * c.d;
  const FloatBand band = FloatBand::make(c.extent, offset, c.d, reach_sq);
  int unsure_count = 0, decided = 0;
  for (int k = 0; k < 200000; ++k) {
    const double xi = c.lo + offset + unit(rng) * (c.extent - 2 * offset);
    const double yi = c.lo + offset + unit(rng) * (c.extent - 2 * offset);
    const double zi = c.lo + offset + unit(rng) * (c.extent - 2 * offset);
    // A random direction, and a distance near d for most pairs.
    double ux = unit(rng) - 0.5, uy = unit(rng) - 0.5, uz = unit(rng) - 0.5;
    const double norm = std::sqrt(ux * ux + uy * uy + uz * uz);
    const double di = diameters ? c.d * (0.5 + unit(rng)) : c.d;
    const double dj = diameters ? std::min(c.d, 2.0 * c.d - di) : c.d;
    const double reach = diameters ? 0.5 * (di + dj) : c.d;
    const double r = k % 4 == 0 ? unit(rng) * offset : reach * (1.0 + (unit(rng) - 0.5) * 2e-5);
    const double xj = xi + r * ux / norm, yj = yi + r * uy / norm, zj = zi + r * uz / norm;
    const double dx = xi - xj, dy = yi - yj, dz = zi - zj;
    const bool exact =
        diameters ? in_contact(dx, dy, dz, di, dj) : in_contact(dx, dy, dz, reach_sq);
    // The float side as the detector computes it: coordinates relative to the box corner.
    const float fx = static_cast<float>(xi - c.lo) - static_cast<float>(xj - c.lo);
    const float fy = static_cast<float>(yi - c.lo) - static_cast<float>(yj - c.lo);
    const float fz = static_cast<float>(zi - c.lo) - static_cast<float>(zj - c.lo);
    bool unsure = false;
    const float s = fx * fx + fy * fy + fz * fz;
    const bool hit =
        diameters
            ? float_contact<true>(s, static_cast<float>(di) + static_cast<float>(dj), band, unsure)
            : float_contact<false>(s, 0.0f, band, unsure);
    if (unsure) {
      ++unsure_count;
      continue;
    }
    ++decided;
    ASSERT_EQ(hit, exact) << "lo " << c.lo << " extent " << c.extent << " d " << c.d << " r " << r;
  }
  // Three quarters of the pairs lie within 1e-5 d of touching, far inside most bands; a
  // quarter are spread over two cells, of which only a thin shell may be unsure.
  EXPECT_GT(decided, 200000 / 5);
}

TEST(FloatBand, DecidesAsDoubleWhereverItIsSure) {
  for (const Case c : {Case{0.0, 1.0, 0.005}, Case{0.0, 1.0, 0.1}, Case{1e6, 1.0, 0.1},
                       Case{-3.0, 100.0, 0.01}, Case{0.0, 1.0, 1e-4}}) {
    check_band(c, false);
    check_band(c, true);
  }
}

TEST(FloatBand, IsThinOnThePaperScene) {
  // D = 1/200 in the unit box: candidates within about 3e-6 of touching (0.06 % of D) only.
  const FloatBand band = FloatBand::make(1.0, 0.01, 0.005, 0.005 * 0.005);
  EXPECT_LT(std::sqrt(band.unsure) - std::sqrt(band.sure), 3e-6);
  EXPECT_GT(band.sure, 0.0f);
}

}  // namespace
}  // namespace contactlab
