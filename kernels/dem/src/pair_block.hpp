// The DEM pair kernels (private to src/): the tangential history law, and a block of the half
// neighbour list packed field by field and put through the contact law on SIMD lanes.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "contactlab/dem/contact_law.hpp"
#include "contactlab/dem/pair_list.hpp"
#include "kin_columns.hpp"

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

// 1 / k_t of a contact of reduced mass m_star [kg] (0 where k_t is 0): per pair it is a
// constant of the list (PairList::inv_kt), per wall contact computed on the spot.
inline double inverse_kt(const PairCoefficients& c, double m_star) {
  const double kt = c.kt_ratio * (c.k_abs + c.k_per_mass * m_star);
  return kt > 0 ? 1.0 / kt : 0.0;
}

// The tangential part of the law for one contact (pair or wall), LAMMPS gran/hooke/history
// with the stored spring projected first: xi <- xi - (xi.n) n; xi += v_t dt; F_t = -k_t xi -
// c_t v_t; at |F_t| > mu F_n: F_t scaled to mu F_n and xi = -(F_t + c_t v_t) / k_t, with
// inv_kt = 1 / k_t given (inverse_kt: the divider is the law's bottleneck on SIMD lanes).
struct Tangential {
  double ftx, fty, ftz;
};

// Always inlined: pair_law's SIMD loop vectorises only with it inside (called, the loop runs
// scalar, and the pair pass took 2.5x as long when a change elsewhere tipped GCC's budget).
[[gnu::always_inline]] inline Tangential tangential(double nx, double ny, double nz, double vtx,
                                                    double vty, double vtz, double fn, double kt,
                                                    double inv_kt, double ct, double mu, double dt,
                                                    double& hx, double& hy, double& hz) {
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
  const double slip_scale = limit / std::sqrt(ft_sq);
  const double scale = slip ? slip_scale : 1.0;
  ftx *= scale;
  fty *= scale;
  ftz *= scale;
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
    kHx,  // the tangential spring and the pair's constants, gathered (pack_pairs: pairs out of
    kHy,  // row order)
    kHz,
    kMstar,
    kInvKt,
    kInputs
  };
  // Force on i [N], n x F_t [N], 1 if touching with a force, the overlap flag (0, 1 above
  // 1 %, 2 above 10 %: one field, not SIMD reductions, which cost a memset a block), rolling
  // torque on i [N m]. The first kRecordFields go into the pairs' records (to_records).
  enum Output {
    kFx,
    kFy,
    kFz,
    kCx,
    kCy,
    kCz,
    kTouch,
    kOverlapFlag,
    kRollX,
    kRollY,
    kRollZ,
    kOutputs
  };
  static constexpr std::size_t kRecordFields = 8;
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
  // Where to_records puts a pair's record (kRecordFields doubles, a cache line): in the
  // inputs' storage, dead once the law has run, from its first 64-byte boundary.
  double* records() {
    static_assert(kInputs >= kRecordFields + 1, "room for the records and the alignment");
    const auto misalignment = reinterpret_cast<std::uintptr_t>(data.data()) % 64 / sizeof(double);
    return data.data() + (misalignment == 0 ? 0 : kRecordFields - misalignment);
  }
};

// The law's outputs kFx .. kOverlapFlag of the block's `count` pairs, one record per pair
// (eight at a time by an in-register transpose): the accumulation then moves a pair with one
// vector load instead of eight loads from eight fields. Returns the records.
inline const double* to_records(PairBlock& blk, std::size_t count) {
  static_assert(PairBlock::kRecordFields == kLanes && PairBlock::kOverlapFlag == kLanes - 1);
  double* rec = blk.records();
  const double* o[kLanes];
  for (std::size_t f = 0; f < kLanes; ++f) o[f] = blk.out(static_cast<PairBlock::Output>(f));
  std::size_t b = 0;
  for (; b + kLanes <= count; b += kLanes) {
    Lanes fields[kLanes], pairs[kLanes];
    for (std::size_t f = 0; f < kLanes; ++f) fields[f] = load_lanes(o[f] + b);
    transpose8(fields, pairs);
    for (std::size_t l = 0; l < kLanes; ++l) store_lanes(rec + kLanes * (b + l), pairs[l]);
  }
  for (; b < count; ++b)
    for (std::size_t f = 0; f < kLanes; ++f) rec[kLanes * b + f] = o[f][b];
  return rec;
}

// What the pack reads of a pair's i particle, held in registers over its row.
struct PackedI {
  double x, y, z, r, vx, vy, vz, m, wx, wy, wz;
  explicit PackedI(const double* ki)
      : x(ki[0]),
        y(ki[1]),
        z(ki[2]),
        r(ki[3]),
        vx(ki[4]),
        vy(ki[5]),
        vz(ki[6]),
        m(ki[7]),
        wx(ki[8]),
        wy(ki[9]),
        wz(ki[10]) {}
};

// The block's input fields, looked up once per pack.
struct PackTargets {
  double* f[PairBlock::kInputs];
  explicit PackTargets(PairBlock& blk) {
    for (int k = 0; k < PairBlock::kInputs; ++k) f[k] = blk.in(static_cast<PairBlock::Input>(k));
  }
};

// Pair k's inputs into the block at b, seen from its i side (the same operations, in the same
// order, as the law on whole particles, so nothing is rounded differently).
template <bool kRolling>
inline void pack_pair(const double* kin, const PairList& q, const PackedI& pi, std::size_t k,
                      std::size_t b, const PackTargets& t) {
  const double* kj = kin + kKinStride * q.j[k];
  const auto& sh = q.shift[q.image[k]];
  const double rj = kj[3];
  t.f[PairBlock::kDx][b] = pi.x - kj[0] - sh[0];
  t.f[PairBlock::kDy][b] = pi.y - kj[1] - sh[1];
  t.f[PairBlock::kDz][b] = pi.z - kj[2] - sh[2];
  t.f[PairBlock::kRr][b] = pi.r + rj;
  t.f[PairBlock::kRmin][b] = rj < pi.r ? rj : pi.r;
  t.f[PairBlock::kDvx][b] = pi.vx - kj[4];
  t.f[PairBlock::kDvy][b] = pi.vy - kj[5];
  t.f[PairBlock::kDvz][b] = pi.vz - kj[6];
  t.f[PairBlock::kSx][b] = pi.r * pi.wx + rj * kj[8];
  t.f[PairBlock::kSy][b] = pi.r * pi.wy + rj * kj[9];
  t.f[PairBlock::kSz][b] = pi.r * pi.wz + rj * kj[10];
  if constexpr (kRolling) {
    t.f[PairBlock::kDwx][b] = pi.wx - kj[8];
    t.f[PairBlock::kDwy][b] = pi.wy - kj[9];
    t.f[PairBlock::kDwz][b] = pi.wz - kj[10];
    t.f[PairBlock::kRprod][b] = pi.r * rj;
  }
}

// Pairs k .. k + 7 into the block at b .. b + 7, as pack_pair would (the same operations on
// the same values, lane by lane), from both particles' kin blocks as columns.
template <bool kRolling>
[[gnu::always_inline]] inline void pack_eight(const double* kin, const PairList& q, std::size_t k,
                                              std::size_t b, const PackTargets& t) {
  const KinColumns pi = kin_columns(kin, kKinStride, q.i.data() + k);
  const KinColumns pj = kin_columns(kin, kKinStride, q.j.data() + k);
  Lanes dx = pi.x - pj.x, dy = pi.y - pj.y, dz = pi.z - pj.z;
  // Periodic images are rare (pairs across a periodic side): x - 0 is x, so skipping the
  // zero shift of eight plain pairs changes no bit.
  std::uint64_t images;
  std::memcpy(&images, q.image.data() + k, sizeof images);
  if (images != 0x0101010101010101u * kNoImage) [[unlikely]] {
    Lanes sx, sy, sz;
    for (std::size_t l = 0; l < kLanes; ++l) {
      const auto& sh = q.shift[q.image[k + l]];
      sx[l] = sh[0];
      sy[l] = sh[1];
      sz[l] = sh[2];
    }
    dx -= sx;
    dy -= sy;
    dz -= sz;
  }
  store_lanes(t.f[PairBlock::kDx] + b, dx);
  store_lanes(t.f[PairBlock::kDy] + b, dy);
  store_lanes(t.f[PairBlock::kDz] + b, dz);
  store_lanes(t.f[PairBlock::kRr] + b, pi.r + pj.r);
  store_lanes(t.f[PairBlock::kRmin] + b, pj.r < pi.r ? pj.r : pi.r);
  store_lanes(t.f[PairBlock::kDvx] + b, pi.vx - pj.vx);
  store_lanes(t.f[PairBlock::kDvy] + b, pi.vy - pj.vy);
  store_lanes(t.f[PairBlock::kDvz] + b, pi.vz - pj.vz);
  store_lanes(t.f[PairBlock::kSx] + b, pi.r * pi.wx + pj.r * pj.wx);
  store_lanes(t.f[PairBlock::kSy] + b, pi.r * pi.wy + pj.r * pj.wy);
  store_lanes(t.f[PairBlock::kSz] + b, pi.r * pi.wz + pj.r * pj.wz);
  if constexpr (kRolling) {
    store_lanes(t.f[PairBlock::kDwx] + b, pi.wx - pj.wx);
    store_lanes(t.f[PairBlock::kDwy] + b, pi.wy - pj.wy);
    store_lanes(t.f[PairBlock::kDwz] + b, pi.wz - pj.wz);
    store_lanes(t.f[PairBlock::kRprod] + b, pi.r * pj.r);
  }
}

// Pack: the rows [first, last) (pairs [rows[first], rows[last])) into the block's inputs,
// eight pairs at a time (pack_eight), the last few one by one.
template <bool kRolling>
inline void pack_rows(const double* kin, const PairList& q, std::size_t first, std::size_t last,
                      PairBlock& blk, const double* acc) {
  const std::size_t k0 = q.rows[first], k1 = q.rows[last];
  const PackTargets t(blk);
  std::size_t k = k0;
  for (; k + kLanes <= k1; k += kLanes) {
    // Partners lie up to max_span particles back (L2 or beyond, out of reach of the hardware
    // prefetcher): fetch the next eight partners' kin blocks and sums.
    for (std::size_t a = k + kPartnerAhead; a < std::min(k + kPartnerAhead + kLanes, q.j.size());
         ++a) {
      const std::size_t ahead = q.j[a];
      __builtin_prefetch(kin + kKinStride * ahead);
      __builtin_prefetch(kin + kKinStride * ahead + kKinStride - 1);
      __builtin_prefetch(acc + kAccStride * ahead, 1);
    }
    pack_eight<kRolling>(kin, q, k, k - k0, t);
  }
  for (; k < k1; ++k) pack_pair<kRolling>(kin, q, PackedI(kin + kKinStride * q.i[k]), k, k - k0, t);
}

// Pack: the pairs pairs[0 .. count) in that order (e.g. a particle's j sides, for the full
// list), each seen from its i side as in pack_rows, with its tangential spring and constants
// gathered into the block (kHx..kInvKt): pair_law then reads and writes the block's copy.
template <bool kRolling>
inline void pack_pairs(const double* kin, const PairList& q, const std::uint32_t* pairs,
                       std::size_t count, PairBlock& blk) {
  const PackTargets t(blk);
  double* hx = t.f[PairBlock::kHx];
  double* hy = t.f[PairBlock::kHy];
  double* hz = t.f[PairBlock::kHz];
  for (std::size_t b = 0; b < count; ++b) {
    const std::uint32_t k = pairs[b];
    if (b + kPartnerAhead < count) {
      __builtin_prefetch(kin + kKinStride * q.i[pairs[b + kPartnerAhead]]);
      __builtin_prefetch(kin + kKinStride * q.i[pairs[b + kPartnerAhead]] + kKinStride - 1);
    }
    pack_pair<kRolling>(kin, q, PackedI(kin + kKinStride * q.i[k]), k, b, t);
    hx[b] = q.hx[k];
    hy[b] = q.hy[k];
    hz[b] = q.hz[k];
    t.f[PairBlock::kMstar][b] = q.m_star[k];
    t.f[PairBlock::kInvKt][b] = q.inv_kt[k];
  }
}

// Where pair_law reads the block's pair constants (m*, 1/k_t) and tangential springs, and
// writes the springs back: the list's own (in place, in_* == out_*), the list's springs into
// their next-step copy (the full list: the springs of this step stay readable for the j
// sides), or a gathered copy in the block.
struct PairView {
  const double *m_star, *inv_kt;
  const double *in_x, *in_y, *in_z;
  double *out_x, *out_y, *out_z;
  static PairView in_place(PairList& q, std::size_t k0) {
    return {q.m_star.data() + k0, q.inv_kt.data() + k0, q.hx.data() + k0, q.hy.data() + k0,
            q.hz.data() + k0,     q.hx.data() + k0,     q.hy.data() + k0, q.hz.data() + k0};
  }
  static PairView to_next(PairList& q, std::size_t k0) {
    return {q.m_star.data() + k0,  q.inv_kt.data() + k0, q.hx.data() + k0,
            q.hy.data() + k0,      q.hz.data() + k0,     q.hx_next.data() + k0,
            q.hy_next.data() + k0, q.hz_next.data() + k0};
  }
  static PairView gathered(PairBlock& blk) {
    double* x = blk.in(PairBlock::kHx);
    double* y = blk.in(PairBlock::kHy);
    double* z = blk.in(PairBlock::kHz);
    return {blk.in(PairBlock::kMstar), blk.in(PairBlock::kInvKt), x, y, z, x, y, z};
  }
};

// The law on the block's `count` packed pairs, each independent of the others, on SIMD lanes (masks
// instead of branches): outputs zero while apart, constants and springs read (and springs
// written) where `pair` says.
// With -ffp-contract=off a lane computes exactly what scalar code would, so where a block boundary
// falls (it moves with the thread count) changes no bit. Overlaps above 1 % are counted into
// `large`, the first above 10 % goes to `bad` (both exact).
template <bool kRolling, bool kClamp>
inline void pair_law(const PairCoefficients& c, double dt, std::size_t count, PairBlock& blk,
                     const PairView& pair) {
  const double* __restrict dx = blk.in(PairBlock::kDx);
  const double* __restrict dy = blk.in(PairBlock::kDy);
  const double* __restrict dz = blk.in(PairBlock::kDz);
  const double* __restrict rr_in = blk.in(PairBlock::kRr);
  const double* __restrict rmin = blk.in(PairBlock::kRmin);
  const double* __restrict m_star_in = pair.m_star;
  const double* __restrict inv_kt = pair.inv_kt;
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
  // Not __restrict: in place, in and out are the same array (omp simd needs no such promise).
  const double* hx_in = pair.in_x;
  const double* hy_in = pair.in_y;
  const double* hz_in = pair.in_z;
  double* hx = pair.out_x;
  double* hy = pair.out_y;
  double* hz = pair.out_z;
  const double k_abs = c.k_abs, k_per_mass = c.k_per_mass, c_per_mass = c.c_per_mass;
  const double kt_ratio = c.kt_ratio, ct_ratio = c.ct_ratio, mu = c.mu, mu_roll = c.mu_roll;
  double* __restrict out_flag = blk.out(PairBlock::kOverlapFlag);
#pragma omp simd
  for (std::uint32_t b = 0; b < static_cast<std::uint32_t>(count); ++b) {
    const double rr = rr_in[b];
    const double rsq = dx[b] * dx[b] + dy[b] * dy[b] + dz[b] * dz[b];
    const bool touch = rsq < rr * rr;
    const double dist = std::sqrt(rsq), inv = 1.0 / dist;
    const double nx = dx[b] * inv, ny = dy[b] * inv, nz = dz[b] * inv;
    const double delta = rr - dist;
    const double flag = delta > kFailFraction * rmin[b] ? 2.0 : 1.0;
    out_flag[b] = touch & (delta > kWarnFraction * rmin[b]) ? flag : 0.0;
    const double m_star = m_star_in[b];
    // Relative velocity of the contact point: v_i - v_j - (r_i w_i + r_j w_j) x n.
    const double sx = sx_in[b], sy = sy_in[b], sz = sz_in[b];
    const double vx = dvx[b] - (sy * nz - sz * ny);
    const double vy = dvy[b] - (sz * nx - sx * nz);
    const double vz = dvz[b] - (sx * ny - sy * nx);
    const double vn = vx * nx + vy * ny + vz * nz;
    const double kn = k_abs + k_per_mass * m_star, cn = c_per_mass * m_star;
    double fn = kn * delta - cn * vn;
    if constexpr (kClamp) fn = fn < 0.0 ? 0.0 : fn;  // std::max(fn, 0.0)
    double sxk = hx_in[b], syk = hy_in[b], szk = hz_in[b];
    const Tangential ft =
        tangential(nx, ny, nz, vx - vn * nx, vy - vn * ny, vz - vn * nz, fn, kt_ratio * kn,
                   inv_kt[b], ct_ratio * cn, mu, dt, sxk, syk, szk);
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

}  // namespace contactlab::dem::detail
