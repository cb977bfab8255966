// The DEM force kernels shared by the engine's loops (private to src/): the tangential
// history law and the pair pass over blocks of the half neighbour list.
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

// What the pair pass reads of a particle, side by side (one or two cache lines per particle
// instead of one per array): x, y, z, r, pvx, pvy, pvz, m, pwx, pwy, pwz, unused.
constexpr std::size_t kKinStride = 12;
// Per particle, kAccStride doubles, summed in pair order by the force pass: force [N],
// torque [N m], touching contacts.
constexpr std::size_t kAccStride = 8;
// How many pairs ahead the pack loop prefetches its partner's data.
constexpr std::size_t kPartnerAhead = 8;
// Rows per block of the pair pass: enough pairs (about 4 a row) for full SIMD lanes, few enough
// that a block's outputs are still in L1 when their particles are gathered.
constexpr std::size_t kRowsPerBlock = 64;

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
  // Branch-free (the pair pass runs this on SIMD lanes): both quotients are computed and the
  // unused one (possibly inf or NaN) is dropped by the selects; slipping implies ft_sq > 0.
  const bool slip = ft_sq > limit * limit;
  const double slip_scale = limit / std::sqrt(ft_sq), kt_inverse = 1.0 / kt;
  const double scale = slip ? slip_scale : 1.0;
  ftx *= scale;
  fty *= scale;
  ftz *= scale;
  const double inv_kt = kt > 0 ? kt_inverse : 0.0;
  hx = slip ? -(ftx + ct * vtx) * inv_kt : hx;
  hy = slip ? -(fty + ct * vty) * inv_kt : hy;
  hz = slip ? -(ftz + ct * vtz) * inv_kt : hz;
  return {ftx, fty, ftz};
}

// One block of pairs, field by field (contiguous, so the law runs on SIMD lanes with plain
// vector loads and stores, no gathers): the inputs the pack loop derives from the two
// particles' kin blocks, and the outputs the law writes.
struct PairBlock {
  enum Input {
    kDx,
    kDy,
    kDz,
    kRr,
    kRmin,
    kMi,
    kMj,
    kDvx,
    kDvy,
    kDvz,
    kSx,
    kSy,
    kSz,
    kDwx,
    kDwy,
    kDwz,
    kRprod,
    kInputs
  };
  // Force on i [N], n x F_t [N], 1 if touching with a force, rolling torque on i [N m], 1 if
  // the overlap is above 1 % / 10 % (flags, not SIMD reductions: those cost a memset a block).
  enum Output {
    kFx,
    kFy,
    kFz,
    kCx,
    kCy,
    kCz,
    kTouch,
    kRollX,
    kRollY,
    kRollZ,
    kLarge,
    kFailing,
    kOutputs
  };
  // The storage is the calling thread's, kept by the engine from step to step (a fresh
  // buffer each step costs page faults and zeroing).
  explicit PairBlock(std::vector<double>& storage) : data(storage) {}
  std::size_t capacity = 0;
  std::vector<double>& data;

  static constexpr std::size_t kFields = std::size_t{kInputs} + kOutputs;
  // Room for `pairs` pairs (the storage only grows; the field stride is its whole length).
  void reserve(std::size_t pairs) {
    capacity = std::max(pairs, data.size() / kFields);
    data.resize(kFields * capacity);
  }
  double* in(Input f) { return data.data() + f * capacity; }
  double* out(Output f) { return data.data() + (std::size_t{kInputs} + f) * capacity; }
};

// Pack: the rows [first, last) (pairs [rows[first], rows[last])), i's values in registers,
// j's from its kin block, into the block's inputs (the same operations, in the same order, as
// the law on whole particles, so nothing is rounded differently).
template <bool kRolling>
inline void pack_rows(const double* kin, const PairList& q, std::size_t first, std::size_t last,
                      PairBlock& blk, double* acc) {
  const std::size_t k0 = q.rows[first];
  double* dx = blk.in(PairBlock::kDx);
  double* dy = blk.in(PairBlock::kDy);
  double* dz = blk.in(PairBlock::kDz);
  double* rr = blk.in(PairBlock::kRr);
  double* rmin = blk.in(PairBlock::kRmin);
  double* mi = blk.in(PairBlock::kMi);
  double* mj = blk.in(PairBlock::kMj);
  double* dvx = blk.in(PairBlock::kDvx);
  double* dvy = blk.in(PairBlock::kDvy);
  double* dvz = blk.in(PairBlock::kDvz);
  double* sx = blk.in(PairBlock::kSx);
  double* sy = blk.in(PairBlock::kSy);
  double* sz = blk.in(PairBlock::kSz);
  for (std::size_t i = first; i < last; ++i) {
    const double* ki = kin + kKinStride * i;
    const double xi = ki[0], yi = ki[1], zi = ki[2], ri = ki[3], vxi = ki[4], vyi = ki[5],
                 vzi = ki[6], m = ki[7], wxi = ki[8], wyi = ki[9], wzi = ki[10];
    for (std::size_t k = q.rows[i]; k < q.rows[i + 1]; ++k) {
      // Partners lie up to max_span particles back (L2 or beyond, out of reach of the hardware
      // prefetcher): fetch the kin block and the sums of the partner a few pairs ahead.
      if (k + kPartnerAhead < q.j.size()) {
        const std::size_t ahead = q.j[k + kPartnerAhead];
        __builtin_prefetch(kin + kKinStride * ahead);
        __builtin_prefetch(kin + kKinStride * ahead + kKinStride - 1);
        __builtin_prefetch(acc + kAccStride * ahead, 1);
      }
      const double* kj = kin + kKinStride * q.j[k];
      const auto& sh = q.shift[q.image[k]];
      const std::size_t b = k - k0;
      const double rj = kj[3];
      dx[b] = xi - kj[0] - sh[0];
      dy[b] = yi - kj[1] - sh[1];
      dz[b] = zi - kj[2] - sh[2];
      rr[b] = ri + rj;
      rmin[b] = rj < ri ? rj : ri;
      mi[b] = m;
      mj[b] = kj[7];
      dvx[b] = vxi - kj[4];
      dvy[b] = vyi - kj[5];
      dvz[b] = vzi - kj[6];
      sx[b] = ri * wxi + rj * kj[8];
      sy[b] = ri * wyi + rj * kj[9];
      sz[b] = ri * wzi + rj * kj[10];
      if constexpr (kRolling) {
        blk.in(PairBlock::kDwx)[b] = wxi - kj[8];
        blk.in(PairBlock::kDwy)[b] = wyi - kj[9];
        blk.in(PairBlock::kDwz)[b] = wzi - kj[10];
        blk.in(PairBlock::kRprod)[b] = ri * rj;
      }
    }
  }
}

// The law on the packed pairs [k0, k1), each independent of the others, on SIMD lanes (masks
// instead of branches): outputs zero while apart, springs updated in place. With
// -ffp-contract=off a lane computes exactly what scalar code would, so where a block boundary
// falls (it moves with the thread count) changes no bit. Overlaps above 1 % are counted into
// `large`, the first above 10 % goes to `bad` (both exact).
template <bool kRolling, bool kClamp>
inline void pair_law(PairList& q, const PairCoefficients& c, double dt, std::size_t k0,
                     std::size_t k1, PairBlock& blk) {
  const double* __restrict dx = blk.in(PairBlock::kDx);
  const double* __restrict dy = blk.in(PairBlock::kDy);
  const double* __restrict dz = blk.in(PairBlock::kDz);
  const double* __restrict rr_in = blk.in(PairBlock::kRr);
  const double* __restrict rmin = blk.in(PairBlock::kRmin);
  const double* __restrict mi = blk.in(PairBlock::kMi);
  const double* __restrict mj = blk.in(PairBlock::kMj);
  const double* __restrict dvx = blk.in(PairBlock::kDvx);
  const double* __restrict dvy = blk.in(PairBlock::kDvy);
  const double* __restrict dvz = blk.in(PairBlock::kDvz);
  const double* __restrict sx_in = blk.in(PairBlock::kSx);
  const double* __restrict sy_in = blk.in(PairBlock::kSy);
  const double* __restrict sz_in = blk.in(PairBlock::kSz);
  const double* __restrict dwx = blk.in(PairBlock::kDwx);
  const double* __restrict dwy = blk.in(PairBlock::kDwy);
  const double* __restrict dwz = blk.in(PairBlock::kDwz);
  const double* __restrict rprod = blk.in(PairBlock::kRprod);
  double* __restrict out_fx = blk.out(PairBlock::kFx);
  double* __restrict out_fy = blk.out(PairBlock::kFy);
  double* __restrict out_fz = blk.out(PairBlock::kFz);
  double* __restrict out_cx = blk.out(PairBlock::kCx);
  double* __restrict out_cy = blk.out(PairBlock::kCy);
  double* __restrict out_cz = blk.out(PairBlock::kCz);
  double* __restrict out_touch = blk.out(PairBlock::kTouch);
  double* __restrict roll_x = blk.out(PairBlock::kRollX);
  double* __restrict roll_y = blk.out(PairBlock::kRollY);
  double* __restrict roll_z = blk.out(PairBlock::kRollZ);
  double* __restrict hx = q.hx.data() + k0;
  double* __restrict hy = q.hy.data() + k0;
  double* __restrict hz = q.hz.data() + k0;
  const double k_abs = c.k_abs, k_per_mass = c.k_per_mass, c_per_mass = c.c_per_mass;
  const double kt_ratio = c.kt_ratio, ct_ratio = c.ct_ratio, mu = c.mu, mu_roll = c.mu_roll;
  double* __restrict out_large = blk.out(PairBlock::kLarge);
  double* __restrict out_failing = blk.out(PairBlock::kFailing);
  const auto count = static_cast<std::uint32_t>(k1 - k0);
#pragma omp simd
  for (std::uint32_t b = 0; b < count; ++b) {
    const double rr = rr_in[b];
    const double rsq = dx[b] * dx[b] + dy[b] * dy[b] + dz[b] * dz[b];
    const bool touch = rsq < rr * rr;
    const double dist = std::sqrt(rsq), inv = 1.0 / dist;
    const double nx = dx[b] * inv, ny = dy[b] * inv, nz = dz[b] * inv;
    const double delta = rr - dist;
    out_large[b] = touch & (delta > kWarnFraction * rmin[b]) ? 1.0 : 0.0;
    out_failing[b] = touch & (delta > kFailFraction * rmin[b]) ? 1.0 : 0.0;
    const double m_star = mi[b] * mj[b] / (mi[b] + mj[b]);
    // Relative velocity of the contact point: v_i - v_j - (r_i w_i + r_j w_j) x n.
    const double sx = sx_in[b], sy = sy_in[b], sz = sz_in[b];
    const double vx = dvx[b] - (sy * nz - sz * ny);
    const double vy = dvy[b] - (sz * nx - sx * nz);
    const double vz = dvz[b] - (sx * ny - sy * nx);
    const double vn = vx * nx + vy * ny + vz * nz;
    const double kn = k_abs + k_per_mass * m_star, cn = c_per_mass * m_star;
    double fn = kn * delta - cn * vn;
    if constexpr (kClamp) fn = fn < 0.0 ? 0.0 : fn;  // std::max(fn, 0.0)
    double sxk = hx[b], syk = hy[b], szk = hz[b];
    const Tangential ft = tangential(nx, ny, nz, vx - vn * nx, vy - vn * ny, vz - vn * nz, fn,
                                     kt_ratio * kn, ct_ratio * cn, mu, dt, sxk, syk, szk);
    hx[b] = touch ? sxk : 0.0;
    hy[b] = touch ? syk : 0.0;
    hz[b] = touch ? szk : 0.0;
    const double fpx = fn * nx + ft.ftx, fpy = fn * ny + ft.fty, fpz = fn * nz + ft.ftz;
    out_fx[b] = touch ? fpx : 0.0;
    out_fy[b] = touch ? fpy : 0.0;
    out_fz[b] = touch ? fpz : 0.0;
    out_cx[b] = touch ? ny * ft.ftz - nz * ft.fty : 0.0;
    out_cy[b] = touch ? nz * ft.ftx - nx * ft.ftz : 0.0;
    out_cz[b] = touch ? nx * ft.fty - ny * ft.ftx : 0.0;
    // A contact with a zero force (e.g. the clamp) does not count as touching.
    out_touch[b] = touch & ((fpx != 0.0) | (fpy != 0.0) | (fpz != 0.0)) ? 1.0 : 0.0;
    if constexpr (kRolling) {
      // Constant rolling-resistance torque against the relative rotation (model A).
      const double ox = dwx[b], oy = dwy[b], oz = dwz[b];
      const double om = std::sqrt(ox * ox + oy * oy + oz * oz);
      const double s_any = -mu_roll * fn * (rprod[b] / rr) / om;  // dropped where om = 0
      const double s = om > 0 ? s_any : 0.0;
      roll_x[b] = touch ? s * ox : 0.0;
      roll_y[b] = touch ? s * oy : 0.0;
      roll_z[b] = touch ? s * oz : 0.0;
    }
  }
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

// Adds the block's pair outputs to the particles' sums in pair order: the i side to acc[i],
// the j side to acc[j] when this thread owns j (j >= own_begin); otherwise the outputs are
// kept in q.out / q.roll_* for j's owner, which adds them after the barrier (they come from
// later rows, so pair order still holds). Particle a's sum is therefore its own row, then its
// j sides in pair order, whatever the thread count.
template <bool kRolling>
inline void accumulate_block(const double* kin, PairList& q, std::size_t k0, std::size_t k1,
                             PairBlock& blk, std::size_t own_begin, double* acc,
                             std::uint64_t& large, std::uint32_t& bad) {
  constexpr std::size_t kOut = PairList::kOutStride;
  const double* o[PairBlock::kOutputs];
  for (int f = 0; f < PairBlock::kOutputs; ++f) o[f] = blk.out(static_cast<PairBlock::Output>(f));
  for (std::size_t k = k0; k < k1; ++k) {
    large += o[PairBlock::kLarge][k - k0] != 0.0;
    if (o[PairBlock::kFailing][k - k0] != 0.0) bad = std::min(bad, static_cast<std::uint32_t>(k));
    const std::size_t b = k - k0;
    const std::uint32_t i = q.i[k], j = q.j[k];
    const double ri = kin[kKinStride * i + 3];
    double* ai = acc + kAccStride * i;
    ai[0] += o[PairBlock::kFx][b];
    ai[1] += o[PairBlock::kFy][b];
    ai[2] += o[PairBlock::kFz][b];
    ai[3] -= ri * o[PairBlock::kCx][b];
    ai[4] -= ri * o[PairBlock::kCy][b];
    ai[5] -= ri * o[PairBlock::kCz][b];
    ai[6] += o[PairBlock::kTouch][b];
    if constexpr (kRolling) {
      ai[3] += o[PairBlock::kRollX][b];
      ai[4] += o[PairBlock::kRollY][b];
      ai[5] += o[PairBlock::kRollZ][b];
    }
    if (j < own_begin) {  // another thread's particle: left for its owner
      for (int f = 0; f <= PairBlock::kTouch; ++f) q.out[kOut * k + f] = o[f][b];
      if constexpr (kRolling) {
        q.roll_x[k] = o[PairBlock::kRollX][b];
        q.roll_y[k] = o[PairBlock::kRollY][b];
        q.roll_z[k] = o[PairBlock::kRollZ][b];
      }
      continue;
    }
    const double rj = kin[kKinStride * j + 3];
    double* aj = acc + kAccStride * j;
    aj[0] -= o[PairBlock::kFx][b];
    aj[1] -= o[PairBlock::kFy][b];
    aj[2] -= o[PairBlock::kFz][b];
    aj[3] -= rj * o[PairBlock::kCx][b];
    aj[4] -= rj * o[PairBlock::kCy][b];
    aj[5] -= rj * o[PairBlock::kCz][b];
    aj[6] += o[PairBlock::kTouch][b];
    if constexpr (kRolling) {
      aj[3] -= o[PairBlock::kRollX][b];
      aj[4] -= o[PairBlock::kRollY][b];
      aj[5] -= o[PairBlock::kRollZ][b];
    }
  }
}

// Adds to particle a's sum the j sides that later threads left in q.out (pairs from rows at
// or after own_end), in pair order.
template <bool kRolling>
inline void accumulate_deferred(const double* kin, const PairList& q, std::size_t a,
                                std::size_t own_end, double* acc) {
  constexpr std::size_t kOut = PairList::kOutStride;
  const double r = kin[kKinStride * a + 3];
  double* aa = acc + kAccStride * a;
  for (std::size_t e = q.j_offsets[a]; e < q.j_offsets[a + 1]; ++e) {
    const std::uint32_t k = q.j_pairs[e];
    if (q.i[k] < own_end) continue;  // added directly
    const double* o = &q.out[kOut * k];
    aa[0] -= o[0];
    aa[1] -= o[1];
    aa[2] -= o[2];
    aa[3] -= r * o[3];
    aa[4] -= r * o[4];
    aa[5] -= r * o[5];
    aa[6] += o[6];
    if constexpr (kRolling) {
      aa[3] -= q.roll_x[k];
      aa[4] -= q.roll_y[k];
      aa[5] -= q.roll_z[k];
    }
  }
}

// The force pass: each thread takes a contiguous range of rows [b, e), computes them a block
// at a time (pack_rows, pair_law on SIMD lanes, accumulate_block) and
// finishes particle a (finish(a, with_walls, large, bad_wall): walls unless serial_walls, when
// walls(a, ...) adds them for every particle in one thread first; gravity, kick) as soon
// as the rows holding its j sides, (a, a + lag], are done; lag = max_span finishes particles
// while their sums are still in cache (fused), lag = n finishes every particle after the
// barrier (split: the pair phase timed alone; `pairs_done` is called once then). The last
// max_span particles of a range wait for the next range's rows, after a barrier. A particle's
// sums do not depend on when it is finished, so the result is the same for any thread count.
template <bool kRolling, bool kClamp, class Finish, class Walls, class PairsDone>
void force_pass(const double* kin, std::size_t n, PairList& q, const PairCoefficients& c, double dt,
                bool fused, bool serial_walls, double* acc, std::vector<double>& scratch,
                Finish& finish, Walls& walls, PairsDone& pairs_done, std::uint64_t& large,
                std::uint32_t& bad_pair, std::uint32_t& bad_wall) {
  const auto t = static_cast<std::size_t>(omp_get_thread_num());
  const auto threads = static_cast<std::size_t>(omp_get_num_threads());
  const std::size_t b = n * t / threads, e = n * (t + 1) / threads;
  const std::size_t lag = fused ? q.max_span : n;
  std::uint64_t large_here = 0;
  std::uint32_t bad_here = UINT32_MAX, bad_wall_here = UINT32_MAX;
  PairBlock blk(scratch);
  std::size_t next = b;  // the next particle to finish
  for (std::size_t first = b; first < e; first += kRowsPerBlock) {
    const std::size_t last = std::min(e, first + kRowsPerBlock);
    const std::size_t k0 = q.rows[first], k1 = q.rows[last];
    blk.reserve(k1 - k0);
    std::fill(acc + kAccStride * first, acc + kAccStride * last, 0.0);
    pack_rows<kRolling>(kin, q, first, last, blk, acc);
    pair_law<kRolling, kClamp>(q, c, dt, k0, k1, blk);
    accumulate_block<kRolling>(kin, q, k0, k1, blk, b, acc, large_here, bad_here);
    for (; next + lag < last; ++next) finish(next, true, large_here, bad_wall_here);
  }
#pragma omp barrier
  pairs_done();
  for (std::size_t a = std::max(next, e > q.max_span ? e - q.max_span : 0); a < e; ++a) {
    accumulate_deferred<kRolling>(kin, q, a, e, acc);
  }
  if (serial_walls) {  // every particle's pairs are in (fused is off: no one finished yet)
#pragma omp barrier
#pragma omp single
    for (std::size_t a = 0; a < n; ++a) walls(a, large_here, bad_wall_here);
  }
  for (; next < e; ++next) finish(next, !serial_walls, large_here, bad_wall_here);
  combine_counts(large_here, bad_here, large, bad_pair);
  combine_counts(0, bad_wall_here, large, bad_wall);
}

}  // namespace contactlab::dem::detail

namespace contactlab::dem::detail {

// Adds a value to a shared sum: atomically (kAtomic: threads may add to the same particle)
// or plainly (a per-thread array).
template <bool kAtomic>
inline void add_to(double& sum, double value) {
  if constexpr (kAtomic) {
#pragma omp atomic
    sum += value;
  } else {
    sum += value;
  }
}

// The block's outputs added to `target` (a thread's own array, or with kAtomic the shared
// one): i's row summed in registers, then added; each j side subtracted.
template <bool kRolling, bool kAtomic>
inline void accumulate_shared(const double* kin, const PairList& q, std::size_t first,
                              std::size_t last, PairBlock& blk, double* target,
                              std::uint64_t& large, std::uint32_t& bad) {
  const double* o[PairBlock::kOutputs];
  for (int f = 0; f < PairBlock::kOutputs; ++f) o[f] = blk.out(static_cast<PairBlock::Output>(f));
  const std::size_t k0 = q.rows[first];
  for (std::size_t i = first; i < last; ++i) {
    const double ri = kin[kKinStride * i + 3];
    double sum[7] = {0, 0, 0, 0, 0, 0, 0};
    for (std::size_t k = q.rows[i]; k < q.rows[i + 1]; ++k) {
      const std::size_t b = k - k0;
      large += o[PairBlock::kLarge][b] != 0.0;
      if (o[PairBlock::kFailing][b] != 0.0) bad = std::min(bad, static_cast<std::uint32_t>(k));
      const double roll[3] = {kRolling ? o[PairBlock::kRollX][b] : 0.0,
                              kRolling ? o[PairBlock::kRollY][b] : 0.0,
                              kRolling ? o[PairBlock::kRollZ][b] : 0.0};
      for (int d = 0; d < 3; ++d) {
        sum[d] += o[PairBlock::kFx + d][b];
        sum[3 + d] -= ri * o[PairBlock::kCx + d][b];
        if constexpr (kRolling) sum[3 + d] += roll[d];
      }
      sum[6] += o[PairBlock::kTouch][b];
      const std::uint32_t j = q.j[k];
      const double rj = kin[kKinStride * j + 3];
      double* aj = target + kAccStride * j;
      for (int d = 0; d < 3; ++d) {
        add_to<kAtomic>(aj[d], -o[PairBlock::kFx + d][b]);
        add_to<kAtomic>(aj[3 + d], -(rj * o[PairBlock::kCx + d][b]) - roll[d]);
      }
      add_to<kAtomic>(aj[6], o[PairBlock::kTouch][b]);
    }
    double* ai = target + kAccStride * i;
    for (int f = 0; f < 7; ++f) add_to<kAtomic>(ai[f], sum[f]);
  }
}

// The force pass of the non-ordered accumulations (per-thread arrays, atomics): blocks of rows
// shared out by the variant's schedule (`omp for schedule(runtime)`: the caller sets it), then
// the per-thread arrays summed in thread order, the walls by one thread when serial_walls, and
// the update (finish(a, with_walls, ...)) shared out by the same schedule.
template <bool kRolling, bool kClamp, class Finish, class Walls, class PairsDone>
void force_pass_shared(const double* kin, std::size_t n, PairList& q, const PairCoefficients& c,
                       double dt, bool atomic, bool serial_walls, double* acc,
                       std::vector<std::vector<double>>& thread_acc, std::vector<double>& scratch,
                       Finish& finish, Walls& walls, PairsDone& pairs_done, std::uint64_t& large,
                       std::uint32_t& bad_pair, std::uint32_t& bad_wall) {
  const auto t = static_cast<std::size_t>(omp_get_thread_num());
  const auto threads = static_cast<std::size_t>(omp_get_num_threads());
  std::uint64_t large_here = 0;
  std::uint32_t bad_here = UINT32_MAX, bad_wall_here = UINT32_MAX;
  double* target = acc;
  if (atomic) {
#pragma omp for schedule(static)
    for (std::size_t a = 0; a < kAccStride * n; ++a) acc[a] = 0.0;
  } else {
    thread_acc[t].assign(kAccStride * n, 0.0);  // the report's cost: one array per thread
    target = thread_acc[t].data();
  }
  PairBlock blk(scratch);
  const std::size_t blocks = (n + kRowsPerBlock - 1) / kRowsPerBlock;
#pragma omp for schedule(runtime) nowait
  for (std::size_t block = 0; block < blocks; ++block) {
    const std::size_t first = block * kRowsPerBlock, last = std::min(n, first + kRowsPerBlock);
    const std::size_t k0 = q.rows[first], k1 = q.rows[last];
    blk.reserve(k1 - k0);
    pack_rows<kRolling>(kin, q, first, last, blk, target);
    pair_law<kRolling, kClamp>(q, c, dt, k0, k1, blk);
    if (atomic) {
      accumulate_shared<kRolling, true>(kin, q, first, last, blk, target, large_here, bad_here);
    } else {
      accumulate_shared<kRolling, false>(kin, q, first, last, blk, target, large_here, bad_here);
    }
  }
#pragma omp barrier
  pairs_done();
  if (!atomic) {  // the reduction, in thread order
#pragma omp for schedule(static)
    for (std::size_t a = 0; a < kAccStride * n; ++a) {
      double sum = thread_acc[0][a];
      for (std::size_t u = 1; u < threads; ++u) sum += thread_acc[u][a];
      acc[a] = sum;
    }
  }
  if (serial_walls) {
#pragma omp single
    for (std::size_t a = 0; a < n; ++a) walls(a, large_here, bad_wall_here);
  }
#pragma omp for schedule(runtime)
  for (std::size_t a = 0; a < n; ++a) finish(a, !serial_walls, large_here, bad_wall_here);
  combine_counts(large_here, bad_here, large, bad_pair);
  combine_counts(0, bad_wall_here, large, bad_wall);
}

}  // namespace contactlab::dem::detail
