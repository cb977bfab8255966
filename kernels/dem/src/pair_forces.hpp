// The DEM force kernels shared by the engine's loops (private to src/): the tangential
// history law and the pair loop over the rows of the half neighbour list.
#pragma once

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "contactlab/dem/contact_law.hpp"
#include "contactlab/dem/pair_list.hpp"

namespace contactlab::dem::detail {

// Overlap thresholds, as fractions of the smaller radius: 1 % and 10 % of the diameter.
constexpr double kWarnFraction = 0.02, kFailFraction = 0.2;

// What the pair loop reads of a particle, side by side (one or two cache lines per partner
// instead of one per array): x, y, z, r, pvx, pvy, pvz, m, pwx, pwy, pwz, unused.
constexpr std::size_t kKinStride = 12;
// How many pairs ahead the pair loop prefetches its partner's block.
constexpr std::size_t kPartnerAhead = 6;

// The tangential part of the law for one contact (pair or wall), LAMMPS gran/hooke/history
// with the stored spring projected first: xi <- xi - (xi.n) n; xi += v_t dt; F_t = -k_t xi -
// c_t v_t; at |F_t| > mu F_n: F_t scaled to mu F_n and xi = -(F_t + c_t v_t) / k_t.
struct Tangential {
  double ftx, fty, ftz;
};

inline Tangential tangential(double nx, double ny, double nz, double vtx, double vty, double vtz,
                             double fn, double kt, double ct, double mu, double dt, double& hx,
                             double& hy, double& hz) {
  const double hn = hx * nx + hy * ny + hz * nz;
  hx += vtx * dt - hn * nx;
  hy += vty * dt - hn * ny;
  hz += vtz * dt - hn * nz;
  double ftx = -kt * hx - ct * vtx, fty = -kt * hy - ct * vty, ftz = -kt * hz - ct * vtz;
  const double ft_sq = ftx * ftx + fty * fty + ftz * ftz;
  const double limit = mu * fn;
  if (ft_sq > limit * limit) {
    const double scale = ft_sq > 0 ? limit / std::sqrt(ft_sq) : 0.0;
    ftx *= scale;
    fty *= scale;
    ftz *= scale;
    const double inv_kt = kt > 0 ? 1.0 / kt : 0.0;
    hx = -(ftx + ct * vtx) * inv_kt;
    hy = -(fty + ct * vty) * inv_kt;
    hz = -(ftz + ct * vtz) * inv_kt;
  }
  return {ftx, fty, ftz};
}

// One row of the half list: the pairs of particle i in list order. i's sums stay in registers
// and go to row_sum; each pair's j side goes to its slot, its spring is updated in place (both
// written only by the thread of the row). Overlaps are counted into large / bad (exact).
template <bool kRolling, bool kClamp>
inline void row_forces(std::size_t i, const double* kin, PairList& q, const PairCoefficients& c,
                       double dt, std::vector<double>& row_sum, std::uint64_t& large_here,
                       std::uint32_t& bad_here) {
  double fx = 0, fy = 0, fz = 0, tx = 0, ty = 0, tz = 0;
  unsigned touching = 0;
  const double* ki = &kin[kKinStride * i];
  const double xi = ki[0], yi = ki[1], zi = ki[2], ri = ki[3], mi = ki[7];
  const double pvxi = ki[4], pvyi = ki[5], pvzi = ki[6];
  const double pwxi = ki[8], pwyi = ki[9], pwzi = ki[10];
  const std::size_t pairs = q.j.size();
  for (std::uint32_t k = q.rows[i]; k < q.rows[i + 1]; ++k) {
    // Partners lie up to two layers of cells back (mostly L2, out of reach of the hardware
    // prefetcher): fetch the block of the partner a few pairs ahead.
    if (k + kPartnerAhead < pairs) __builtin_prefetch(&kin[kKinStride * q.j[k + kPartnerAhead]]);
    const double* kj = &kin[kKinStride * q.j[k]];
    const auto& sh = q.shift[q.image[k]];
    const double dx = xi - kj[0] - sh[0], dy = yi - kj[1] - sh[1], dz = zi - kj[2] - sh[2];
    const double rj = kj[3], rr = ri + rj;
    const double rsq = dx * dx + dy * dy + dz * dz;
    const std::size_t slot = q.j_slot[k];
    double* out = &q.out[6 * slot];
    if (rsq >= rr * rr) {
      q.hx[k] = q.hy[k] = q.hz[k] = 0.0;
      out[0] = out[1] = out[2] = out[3] = out[4] = out[5] = 0.0;
      if constexpr (kRolling) q.roll[3 * slot] = q.roll[3 * slot + 1] = q.roll[3 * slot + 2] = 0.0;
      continue;
    }
    const double dist = std::sqrt(rsq), inv = 1.0 / dist;
    const double nx = dx * inv, ny = dy * inv, nz = dz * inv;
    const double delta = rr - dist;
    const double r_min = std::min(ri, rj);
    large_here += delta > kWarnFraction * r_min;
    if (delta > kFailFraction * r_min) bad_here = std::min(bad_here, k);
    const double mj = kj[7];
    const double m_star = mi * mj / (mi + mj);
    // Relative velocity of the contact point: v_i - v_j - (r_i w_i + r_j w_j) x n.
    const double sx = ri * pwxi + rj * kj[8], sy = ri * pwyi + rj * kj[9],
                 sz = ri * pwzi + rj * kj[10];
    const double vx = pvxi - kj[4] - (sy * nz - sz * ny);
    const double vy = pvyi - kj[5] - (sz * nx - sx * nz);
    const double vz = pvzi - kj[6] - (sx * ny - sy * nx);
    const double vn = vx * nx + vy * ny + vz * nz;
    const double kn = c.k_abs + c.k_per_mass * m_star, cn = c.c_per_mass * m_star;
    double fn = kn * delta - cn * vn;
    if constexpr (kClamp) fn = std::max(fn, 0.0);
    const Tangential ft =
        tangential(nx, ny, nz, vx - vn * nx, vy - vn * ny, vz - vn * nz, fn, c.kt_ratio * kn,
                   c.ct_ratio * cn, c.mu, dt, q.hx[k], q.hy[k], q.hz[k]);
    const double fpx = fn * nx + ft.ftx, fpy = fn * ny + ft.fty, fpz = fn * nz + ft.ftz;
    const double cx = ny * ft.ftz - nz * ft.fty, cy = nz * ft.ftx - nx * ft.ftz,
                 cz = nx * ft.fty - ny * ft.ftx;
    out[0] = fpx;
    out[1] = fpy;
    out[2] = fpz;
    out[3] = cx;
    out[4] = cy;
    out[5] = cz;
    fx += fpx;
    fy += fpy;
    fz += fpz;
    tx -= ri * cx;
    ty -= ri * cy;
    tz -= ri * cz;
    touching += (fpx != 0.0) | (fpy != 0.0) | (fpz != 0.0);
    if constexpr (kRolling) {
      // Constant rolling-resistance torque against the relative rotation (model A).
      const double ox = pwxi - kj[8], oy = pwyi - kj[9], oz = pwzi - kj[10];
      const double om = std::sqrt(ox * ox + oy * oy + oz * oz);
      const double s = om > 0 ? -c.mu_roll * fn * (ri * rj / rr) / om : 0.0;
      q.roll[3 * slot] = s * ox;
      q.roll[3 * slot + 1] = s * oy;
      q.roll[3 * slot + 2] = s * oz;
      tx += s * ox;
      ty += s * oy;
      tz += s * oz;
    }
  }
  double* sum = &row_sum[7 * i];
  sum[0] = fx;
  sum[1] = fy;
  sum[2] = fz;
  sum[3] = tx;
  sum[4] = ty;
  sum[5] = tz;
  sum[6] = touching;
}

// Combines a thread's overlap counts into the shared ones (integers: exact in any order).
inline void combine_counts(std::uint64_t here, std::uint32_t bad_here, std::uint64_t& total,
                           std::uint32_t& bad) {
  if (here > 0) {
#pragma omp atomic
    total += here;
  }
  if (bad_here != UINT32_MAX) {
#pragma omp critical(dem_bad_index)
    bad = std::min(bad, bad_here);
  }
}

// The pair loop alone (for the phase split): rows shared out by `omp for` (orphaned: called
// inside the parallel region).
template <bool kRolling, bool kClamp>
void pair_rows(const double* kin, std::size_t n, PairList& q, const PairCoefficients& c, double dt,
               std::vector<double>& row_sum, std::uint64_t& large, std::uint32_t& bad_pair) {
  std::uint64_t large_here = 0;
  std::uint32_t bad_here = UINT32_MAX;
#pragma omp for schedule(static)
  for (std::size_t i = 0; i < n; ++i) {
    row_forces<kRolling, kClamp>(i, kin, q, c, dt, row_sum, large_here, bad_here);
  }
  combine_counts(large_here, bad_here, large, bad_pair);
}

// The fused pass: each thread takes a contiguous block of rows [b, e) and gathers particle a
// as soon as the rows holding its j sides, (a, a + max_span], are done (they are still in
// cache); the last max_span particles of the block wait for the next block's rows, after a
// barrier. gather(a, large, bad_wall) does a particle's gather, walls, gravity and kick; its
// sums do not depend on when it runs, so the result is the same for any thread count.
template <bool kRolling, bool kClamp, class Gather>
void fused_pass(const double* kin, std::size_t n, PairList& q, const PairCoefficients& c, double dt,
                std::vector<double>& row_sum, Gather& gather, std::uint64_t& large,
                std::uint32_t& bad_pair, std::uint32_t& bad_wall) {
  const auto t = static_cast<std::size_t>(omp_get_thread_num());
  const auto threads = static_cast<std::size_t>(omp_get_num_threads());
  const std::size_t b = n * t / threads, e = n * (t + 1) / threads, lag = q.max_span;
  std::uint64_t large_here = 0;
  std::uint32_t bad_here = UINT32_MAX, bad_wall_here = UINT32_MAX;
  for (std::size_t i = b; i < e; ++i) {
    row_forces<kRolling, kClamp>(i, kin, q, c, dt, row_sum, large_here, bad_here);
    if (i >= b + lag) gather(i - lag, large_here, bad_wall_here);
  }
#pragma omp barrier
  for (std::size_t a = e > b + lag ? e - lag : b; a < e; ++a) {
    gather(a, large_here, bad_wall_here);
  }
  combine_counts(large_here, bad_here, large, bad_pair);
  combine_counts(0, bad_wall_here, large, bad_wall);
}

}  // namespace contactlab::dem::detail
