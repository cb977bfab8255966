// The DEM pair kernel (private to src/): a block of the neighbour list through the contact
// law eight pairs at a time in registers (both particles' kin blocks loaded and transposed,
// the law on SIMD lanes, its outputs transposed into one record per pair; with AVX-512 two
// such groups at once, as two chains: lane_pair.hpp), the last few pairs one by one with the
// same law on doubles.
// Compiled once per instruction set (dem_isa.hpp): a toggle, no include guard.

#include <unistd.h>  // sysconf: the L2's size

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "contactlab/dem/contact_law.hpp"
#include "contactlab/dem/pair_list.hpp"
#include "dem_isa.hpp"
#include "kin_columns.hpp"
#include "lane_pair.hpp"
#include "lanes.hpp"

#if defined(CONTACTLAB_DEM_PAIR_BLOCK_TOGGLE) == defined(CONTACTLAB_DEM_ISA_TOGGLE)
#ifdef CONTACTLAB_DEM_PAIR_BLOCK_TOGGLE
#undef CONTACTLAB_DEM_PAIR_BLOCK_TOGGLE
#else
#define CONTACTLAB_DEM_PAIR_BLOCK_TOGGLE
#endif

namespace contactlab::dem::detail {
CONTACTLAB_DEM_ISA_NAMESPACE(build) {

// Overlap thresholds, as fractions of the smaller radius: 1 % and 10 % of the diameter.
constexpr double kWarnFraction = 0.02, kFailFraction = 0.2;

// What the pair pass reads of a particle, side by side (one or two cache lines per particle
// instead of one per array): x, y, z, r, pvx, pvy, pvz, m, pwx, pwy, pwz, unused.
constexpr std::size_t kKinStride = 12;
// Per particle, kAccStride doubles, summed in pair order by the force pass: force [N],
// torque [N m], touching contacts.
constexpr std::size_t kAccStride = 8;
// Whether the pair kernel puts two groups of eight pairs through the law at once (lane_pair.hpp):
// where a register holds eight doubles.
constexpr bool kTwoGroups = kLaneParts == 1;
// How many pairs ahead the pair kernel prefetches its partners' kin blocks (8, one group, was 3 %
// slower on the bed: the partners arrived late). Their sums' lines are not prefetched: read by
// the sums after the whole block, they had left L1 by then (no difference with or without).
constexpr std::size_t kPartnerAhead = 32;

// The bytes of L2 a core has (sysconf; 1 MiB where the system does not say).
inline std::size_t l2_bytes() {
  static const std::size_t bytes = [] {
    const long b = sysconf(_SC_LEVEL2_CACHE_SIZE);
    return b > 0 ? static_cast<std::size_t>(b) : std::size_t{1} << 20;
  }();
  return bytes;
}

// Whether the pair kernel prefetches the partners of a list whose pairs reach max_span particles
// back. Always on four lanes (AVX2: 0.98x the bed's step without). Where two groups go at once
// (AVX-512) only if the partners' blocks and sums within that span (160 bytes a particle) fill more
// than half of L2: on the settled bed's near pairs (0.8 MB of them, a 2 MiB L2) they are there
// from their own rows and the loop is bound by its instructions, which the prefetches added to
// (the step without them, interleaved on a Xeon: 1.02 - 1.03x at one thread, 1.02 - 1.04x at
// two), where the 900,000-particle hopper, its partners megabytes back, ran 12 % slower without.
inline bool prefetch_partners_of(std::size_t max_span) {
  return !kTwoGroups || max_span * (kKinStride + kAccStride) * sizeof(double) > l2_bytes() / 2;
}

// 1 / k_t of a contact of reduced mass m_star [kg] (0 where k_t is 0): per pair it is a
// constant of the list (PairList::inv_kt), per wall contact computed on the spot.
inline double inverse_kt(const PairCoefficients& c, double m_star) {
  const double kt = c.kt_ratio * c.k_n(m_star);
  return kt > 0 ? 1.0 / kt : 0.0;
}

// The law is written once for V = double (one contact: walls, a block's last pairs) and
// V = Lanes (eight pairs); a mask is a bool or a lane mask, and these pick or fill either.
template <class V>
[[gnu::always_inline]] inline V splat(double x) {
  return V{} + x;
}
[[gnu::always_inline]] inline double sqrt_of(double x) { return std::sqrt(x); }
[[gnu::always_inline]] inline Lanes sqrt_of(const Lanes& x) { return sqrt_lanes(x); }

template <class V>
struct Tangential {
  V ftx, fty, ftz;
};

// The tangential part of the law for one contact (pair or wall), LAMMPS gran/hooke/history
// with the stored spring projected first: xi <- xi - (xi.n) n; xi += v_t dt; F_t = -k_t xi -
// c_t v_t; at |F_t| > mu F_n: F_t scaled to mu F_n and xi = -(F_t + c_t v_t) / k_t, with
// inv_kt = 1 / k_t given (inverse_kt: the divider is the law's bottleneck on SIMD lanes).
// Branch-free: both quotients are computed and the unused one (possibly inf or NaN) is
// dropped by the selects; slipping implies ft_sq > 0.
template <class V>
[[gnu::always_inline]] inline Tangential<V> tangential(V nx, V ny, V nz, V vtx, V vty, V vtz, V fn,
                                                       V kt, V inv_kt, V ct, double mu, double dt,
                                                       V& hx, V& hy, V& hz) {
  const V hn = hx * nx + hy * ny + hz * nz;
  hx += vtx * dt - hn * nx;
  hy += vty * dt - hn * ny;
  hz += vtz * dt - hn * nz;
  V ftx = -kt * hx - ct * vtx, fty = -kt * hy - ct * vty, ftz = -kt * hz - ct * vtz;
  const V ft_sq = ftx * ftx + fty * fty + ftz * ftz;
  const V limit = mu * fn;
  const auto slip = ft_sq > limit * limit;
  const V scale = select(slip, limit / sqrt_of(ft_sq), splat<V>(1.0));
  ftx *= scale;
  fty *= scale;
  ftz *= scale;
  hx = select(slip, -(ftx + ct * vtx) * inv_kt, hx);
  hy = select(slip, -(fty + ct * vty) * inv_kt, hy);
  hz = select(slip, -(ftz + ct * vtz) * inv_kt, hz);
  return {ftx, fty, ftz};
}

// What the law reads of a pair (V = double) or of eight (Lanes), seen from the i side: the
// separation with the image shift, r_i + r_j, the smaller radius, v_i - v_j, r_i w_i + r_j w_j,
// and for rolling resistance w_i - w_j and r_i r_j. Its constants (PairList::m_star, inv_kt)
// and tangential spring come from the list.
template <class V>
struct PairInputs {
  V dx, dy, dz, rr, rmin, dvx, dvy, dvz, sx, sy, sz, dwx, dwy, dwz, rprod;
  V m_star, inv_kt;
  V hx, hy, hz;  // in: the spring of the last step; out: this step's
};

// The law's results for a pair: force on i [N], n x F_t [N], 1 if touching with a force, the
// overlap flag (0, 1 above 1 %, 2 above 10 % of the smaller diameter) and the rolling torque
// on i [N m]. The first eight are a pair's record, in this order.
template <class V>
struct PairOutputs {
  V fx, fy, fz, cx, cy, cz, touch, flag, roll_x, roll_y, roll_z;
};

// Two groups' inputs as one value of the law, and one group's outputs (TwoGroups::a or ::b).
// clang-format off
[[gnu::always_inline]] inline PairInputs<TwoGroups> side_by_side(const PairInputs<Lanes>& a,
                                                                 const PairInputs<Lanes>& b) {
  PairInputs<TwoGroups> r;
#define CONTACTLAB_FIELD(f) r.f = {a.f, b.f};
  CONTACTLAB_FIELD(dx) CONTACTLAB_FIELD(dy) CONTACTLAB_FIELD(dz) CONTACTLAB_FIELD(rr)
  CONTACTLAB_FIELD(rmin) CONTACTLAB_FIELD(dvx) CONTACTLAB_FIELD(dvy) CONTACTLAB_FIELD(dvz)
  CONTACTLAB_FIELD(sx) CONTACTLAB_FIELD(sy) CONTACTLAB_FIELD(sz) CONTACTLAB_FIELD(dwx)
  CONTACTLAB_FIELD(dwy) CONTACTLAB_FIELD(dwz) CONTACTLAB_FIELD(rprod) CONTACTLAB_FIELD(m_star)
  CONTACTLAB_FIELD(inv_kt) CONTACTLAB_FIELD(hx) CONTACTLAB_FIELD(hy) CONTACTLAB_FIELD(hz)
#undef CONTACTLAB_FIELD
  return r;
}
[[gnu::always_inline]] inline PairOutputs<Lanes> group_of(const PairOutputs<TwoGroups>& o,
                                                          Lanes TwoGroups::*group) {
  PairOutputs<Lanes> r;
#define CONTACTLAB_FIELD(f) r.f = o.f.*group;
  CONTACTLAB_FIELD(fx) CONTACTLAB_FIELD(fy) CONTACTLAB_FIELD(fz) CONTACTLAB_FIELD(cx)
  CONTACTLAB_FIELD(cy) CONTACTLAB_FIELD(cz) CONTACTLAB_FIELD(touch) CONTACTLAB_FIELD(flag)
  CONTACTLAB_FIELD(roll_x) CONTACTLAB_FIELD(roll_y) CONTACTLAB_FIELD(roll_z)
#undef CONTACTLAB_FIELD
  return r;
}
// clang-format on

// The contact law on one pair or eight (outputs zero while apart). With -ffp-contract=off a
// lane computes exactly what the one-pair form computes, so where a block boundary falls (it
// moves with the thread count) changes no bit.
template <bool kRolling, bool kClamp, class V>
[[gnu::always_inline]] inline PairOutputs<V> pair_law(const PairCoefficients& c, double dt,
                                                      PairInputs<V>& in) {
  const V dx = in.dx, dy = in.dy, dz = in.dz, rr = in.rr;
  const V rsq = dx * dx + dy * dy + dz * dz;
  const auto touch = rsq < rr * rr;
  const V dist = sqrt_of(rsq), inv = 1.0 / dist;
  const V nx = dx * inv, ny = dy * inv, nz = dz * inv;
  const V delta = rr - dist;
  const V zero{}, one = splat<V>(1.0);
  PairOutputs<V> out;
  const V flag = select(delta > kFailFraction * in.rmin, splat<V>(2.0), one);
  out.flag = select(touch & (delta > kWarnFraction * in.rmin), flag, zero);
  // Relative velocity of the contact point: v_i - v_j - (r_i w_i + r_j w_j) x n.
  const V sx = in.sx, sy = in.sy, sz = in.sz;
  const V vx = in.dvx - (sy * nz - sz * ny);
  const V vy = in.dvy - (sz * nx - sx * nz);
  const V vz = in.dvz - (sx * ny - sy * nx);
  const V vn = vx * nx + vy * ny + vz * nz;
  const V kn = c.k_abs + c.k_per_mass * in.m_star, cn = c.c_per_mass * in.m_star;
  V fn = kn * delta - cn * vn;
  if constexpr (kClamp) fn = select(fn < 0.0, zero, fn);  // std::max(fn, 0.0)
  V hx = in.hx, hy = in.hy, hz = in.hz;
  const Tangential<V> ft =
      tangential<V>(nx, ny, nz, vx - vn * nx, vy - vn * ny, vz - vn * nz, fn, c.kt_ratio * kn,
                    in.inv_kt, c.ct_ratio * cn, c.mu, dt, hx, hy, hz);
  in.hx = select(touch, hx, zero);
  in.hy = select(touch, hy, zero);
  in.hz = select(touch, hz, zero);
  const V fpx = fn * nx + ft.ftx, fpy = fn * ny + ft.fty, fpz = fn * nz + ft.ftz;
  out.fx = select(touch, fpx, zero);
  out.fy = select(touch, fpy, zero);
  out.fz = select(touch, fpz, zero);
  out.cx = select(touch, ny * ft.ftz - nz * ft.fty, zero);
  out.cy = select(touch, nz * ft.ftx - nx * ft.ftz, zero);
  out.cz = select(touch, nx * ft.fty - ny * ft.ftx, zero);
  // A contact with a zero force (e.g. the clamp) does not count as touching.
  out.touch = select(touch & ((fpx != 0.0) | (fpy != 0.0) | (fpz != 0.0)), one, zero);
  if constexpr (kRolling) {
    // Constant rolling-resistance torque against the relative rotation (model A).
    const V ox = in.dwx, oy = in.dwy, oz = in.dwz;
    const V om = sqrt_of(ox * ox + oy * oy + oz * oz);
    const V s_any = -c.mu_roll * fn * (in.rprod / rr) / om;  // dropped where om = 0
    const V s = select(om > 0.0, s_any, zero);
    out.roll_x = select(touch, s * ox, zero);
    out.roll_y = select(touch, s * oy, zero);
    out.roll_z = select(touch, s * oz, zero);
  }
  return out;
}

// Pair k's inputs from its particles' kin blocks (the same operations, in the same order, as
// the eight-lane pack, so nothing is rounded differently).
template <bool kRolling>
inline PairInputs<double> pack_one(const double* kin, const PairList& q, std::size_t k) {
  const double* ki = kin + kKinStride * q.i[k];
  const double* kj = kin + kKinStride * q.j[k];
  const auto& sh = q.shift[q.image[k]];
  const double ri = ki[3], rj = kj[3];
  PairInputs<double> in{};
  in.dx = ki[0] - kj[0] - sh[0];
  in.dy = ki[1] - kj[1] - sh[1];
  in.dz = ki[2] - kj[2] - sh[2];
  in.rr = ri + rj;
  in.rmin = select(rj < ri, rj, ri);
  in.dvx = ki[4] - kj[4];
  in.dvy = ki[5] - kj[5];
  in.dvz = ki[6] - kj[6];
  in.sx = ri * ki[8] + rj * kj[8];
  in.sy = ri * ki[9] + rj * kj[9];
  in.sz = ri * ki[10] + rj * kj[10];
  if constexpr (kRolling) {
    in.dwx = ki[8] - kj[8];
    in.dwy = ki[9] - kj[9];
    in.dwz = ki[10] - kj[10];
    in.rprod = ri * rj;
  }
  in.m_star = q.m_star[k];
  in.inv_kt = q.inv_kt[k];
  in.hx = q.hx[k];
  in.hy = q.hy[k];
  in.hz = q.hz[k];
  return in;
}

// The eight pairs whose i and j are ii[0..7], jj[0..7] and image codes images[0..7], from both
// particles' kin blocks as columns; constants and springs are the caller's to fill.
template <bool kRolling>
[[gnu::always_inline]] inline PairInputs<Lanes> pack_eight(const double* kin, const PairList& q,
                                                           const std::uint32_t* ii,
                                                           const std::uint32_t* jj,
                                                           const std::uint8_t* images) {
  const KinColumns pi = kin_columns(kin, kKinStride, ii);
  const KinColumns pj = kin_columns(kin, kKinStride, jj);
  PairInputs<Lanes> in{};
  in.dx = pi.x - pj.x;
  in.dy = pi.y - pj.y;
  in.dz = pi.z - pj.z;
  // Periodic images are rare (pairs across a periodic side): x - 0 is x, so skipping the
  // zero shift of eight plain pairs changes no bit.
  std::uint64_t codes;
  std::memcpy(&codes, images, sizeof codes);
  if (codes != 0x0101010101010101u * kNoImage) [[unlikely]] {
    double sx[kLanes], sy[kLanes], sz[kLanes];
    for (std::size_t l = 0; l < kLanes; ++l) {
      const auto& sh = q.shift[images[l]];
      sx[l] = sh[0];
      sy[l] = sh[1];
      sz[l] = sh[2];
    }
    in.dx -= lanes_of(sx);
    in.dy -= lanes_of(sy);
    in.dz -= lanes_of(sz);
  }
  in.rr = pi.r + pj.r;
  in.rmin = select(pj.r < pi.r, pj.r, pi.r);
  in.dvx = pi.vx - pj.vx;
  in.dvy = pi.vy - pj.vy;
  in.dvz = pi.vz - pj.vz;
  in.sx = pi.r * pi.wx + pj.r * pj.wx;
  in.sy = pi.r * pi.wy + pj.r * pj.wy;
  in.sz = pi.r * pi.wz + pj.r * pj.wz;
  if constexpr (kRolling) {
    in.dwx = pi.wx - pj.wx;
    in.dwy = pi.wy - pj.wy;
    in.dwz = pi.wz - pj.wz;
    in.rprod = pi.r * pj.r;
  }
  return in;
}

// A block's results: one record of eight doubles (a cache line) per pair, PairOutputs' first
// eight fields, so the sums move a pair with one vector load; with rolling resistance, the
// rolling torques as three fields. The storage is the calling thread's, kept by the engine
// from step to step (a fresh buffer each step costs page faults and zeroing).
struct PairBlock {
  enum RecordField { kFx, kFy, kFz, kCx, kCy, kCz, kTouch, kOverlapFlag };
  static constexpr std::size_t kRecordFields = 8;
  explicit PairBlock(std::vector<double>& storage) : data(storage) {}
  std::size_t capacity = 0;
  std::vector<double>& data;

  // Room for `pairs` pairs (the storage only grows).
  void reserve(std::size_t pairs) {
    capacity = std::max(pairs, capacity);
    data.resize(std::max(data.size(), (kRecordFields + 3) * capacity + kRecordFields));
  }
  // From the storage's first 64-byte boundary.
  double* records() {
    const auto misalignment = reinterpret_cast<std::uintptr_t>(data.data()) % 64 / sizeof(double);
    return data.data() + (misalignment == 0 ? 0 : kRecordFields - misalignment);
  }
  double* roll(int axis) { return records() + kRecordFields * capacity + axis * capacity; }
};

// Stores pair b's outputs (one pair, or eight from b on) into the block's records and rolling
// fields, and counts its overlaps (above 1 % into large, the first above 10 % into bad, by
// its pair index k0 + b) where `count_overlaps` (each pair is counted once, by its row).
template <bool kRolling>
inline void store_outputs(PairBlock& blk, std::size_t b, const PairOutputs<double>& o,
                          bool count_overlaps, std::size_t k0, std::uint64_t& large,
                          std::uint32_t& bad) {
  double* rec = blk.records() + PairBlock::kRecordFields * b;
  const double fields[PairBlock::kRecordFields] = {o.fx, o.fy, o.fz,    o.cx,
                                                   o.cy, o.cz, o.touch, o.flag};
  std::memcpy(rec, fields, sizeof fields);
  if constexpr (kRolling) {
    blk.roll(0)[b] = o.roll_x;
    blk.roll(1)[b] = o.roll_y;
    blk.roll(2)[b] = o.roll_z;
  }
  if (count_overlaps && o.flag != 0.0) {
    ++large;
    if (o.flag > 1.0) bad = std::min(bad, static_cast<std::uint32_t>(k0 + b));
  }
}
template <bool kRolling>
inline void store_outputs(PairBlock& blk, std::size_t b, const PairOutputs<Lanes>& o,
                          bool count_overlaps, std::size_t k0, std::uint64_t& large,
                          std::uint32_t& bad) {
  const Lanes fields[kLanes] = {o.fx, o.fy, o.fz, o.cx, o.cy, o.cz, o.touch, o.flag};
  store_transposed(fields, blk.records() + PairBlock::kRecordFields * b, PairBlock::kRecordFields);
  if constexpr (kRolling) {
    store_lanes(blk.roll(0) + b, o.roll_x);
    store_lanes(blk.roll(1) + b, o.roll_y);
    store_lanes(blk.roll(2) + b, o.roll_z);
  }
  // A settled bed has a handful of overlaps above 1 % a step: test eight at once.
  if (count_overlaps && any_set(o.flag != 0.0)) [[unlikely]] {
    for (std::size_t l = 0; l < kLanes; ++l) {
      if (o.flag[l] == 0.0) continue;
      ++large;
      if (o.flag[l] > 1.0) bad = std::min(bad, static_cast<std::uint32_t>(k0 + b + l));
    }
  }
}

// Where pair_rows puts the new tangential springs: back into the list (in place), or into its
// next-step copy (the full list: the springs of this step stay readable for its j sides).
enum class SpringsTo { kList, kNext };

// The rows [first, last) (pairs [rows[first], rows[last])) through the law: eight pairs at a
// time (pack_eight, pair_law on lanes, store_outputs), the last few one by one. Records land
// at b = k - rows[first].
template <bool kRolling, bool kClamp>
inline void pair_rows(const double* kin, PairList& q, const PairCoefficients& c, double dt,
                      std::size_t first, std::size_t last, SpringsTo springs, PairBlock& blk,
                      std::uint64_t& large, std::uint32_t& bad) {
  const std::size_t k0 = q.rows[first], k1 = q.rows[last];
  blk.reserve(k1 - k0);
  double* hx_out = (springs == SpringsTo::kNext ? q.hx_next : q.hx).data();
  double* hy_out = (springs == SpringsTo::kNext ? q.hy_next : q.hy).data();
  double* hz_out = (springs == SpringsTo::kNext ? q.hz_next : q.hz).data();
  // Three steps of a group, each inlined by force: called from two loops, they were calls, the
  // inputs went through memory, and the step ran at 0.7 of its speed.
  // Partners lie up to max_span particles back (L2 or beyond, out of reach of the hardware
  // prefetcher): the kin blocks of those of pairs [k, k + count) + kPartnerAhead.
  const bool prefetch = prefetch_partners_of(q.max_span);
  auto prefetch_partners = [&](std::size_t k, std::size_t count) __attribute__((always_inline)) {
    if (!prefetch) return;
    for (std::size_t a = k + kPartnerAhead; a < std::min(k + kPartnerAhead + count, q.j.size());
         ++a) {
      const std::size_t ahead = q.j[a];
      __builtin_prefetch(kin + kKinStride * ahead);
      __builtin_prefetch(kin + kKinStride * ahead + kKinStride - 1);
    }
  };
  // Pairs [k, k + 8): their inputs, and where their springs and records go.
  auto pack_group = [&](std::size_t k) __attribute__((always_inline)) {
    PairInputs<Lanes> in =
        pack_eight<kRolling>(kin, q, q.i.data() + k, q.j.data() + k, q.image.data() + k);
    in.m_star = load_lanes(q.m_star.data() + k);
    in.inv_kt = load_lanes(q.inv_kt.data() + k);
    in.hx = load_lanes(q.hx.data() + k);
    in.hy = load_lanes(q.hy.data() + k);
    in.hz = load_lanes(q.hz.data() + k);
    return in;
  };
  auto store_group = [&](std::size_t k, const Lanes& hx, const Lanes& hy, const Lanes& hz,
                         const PairOutputs<Lanes>& out) __attribute__((always_inline)) {
    store_lanes(hx_out + k, hx);
    store_lanes(hy_out + k, hy);
    store_lanes(hz_out + k, hz);
    store_outputs<kRolling>(blk, k - k0, out, true, k0, large, bad);
  };
  std::size_t k = k0;
  if constexpr (kTwoGroups) {
    for (; k + 2 * kLanes <= k1; k += 2 * kLanes) {
      prefetch_partners(k, 2 * kLanes);
      PairInputs<TwoGroups> in = side_by_side(pack_group(k), pack_group(k + kLanes));
      const PairOutputs<TwoGroups> out = pair_law<kRolling, kClamp>(c, dt, in);
      store_group(k, in.hx.a, in.hy.a, in.hz.a, group_of(out, &TwoGroups::a));
      store_group(k + kLanes, in.hx.b, in.hy.b, in.hz.b, group_of(out, &TwoGroups::b));
    }
  }
  for (; k + kLanes <= k1; k += kLanes) {
    prefetch_partners(k, kLanes);
    PairInputs<Lanes> in = pack_group(k);
    const PairOutputs<Lanes> out = pair_law<kRolling, kClamp>(c, dt, in);
    store_group(k, in.hx, in.hy, in.hz, out);
  }
  for (; k < k1; ++k) {
    PairInputs<double> in = pack_one<kRolling>(kin, q, k);
    const PairOutputs<double> out = pair_law<kRolling, kClamp>(c, dt, in);
    hx_out[k] = in.hx;
    hy_out[k] = in.hy;
    hz_out[k] = in.hz;
    store_outputs<kRolling>(blk, k - k0, out, true, k0, large, bad);
  }
}

// The pairs pairs[0 .. count) in that order (a block's j sides, for the full list), each seen
// from its i side as in pair_rows, from the springs of this step (their new values are
// dropped: the pair's row keeps them); overlaps are not counted (the rows count them).
template <bool kRolling, bool kClamp>
inline void pair_gathered(const double* kin, const PairList& q, const PairCoefficients& c,
                          double dt, const std::uint32_t* pairs, std::size_t count,
                          PairBlock& blk) {
  blk.reserve(count);
  std::uint64_t unused_large = 0;
  std::uint32_t unused_bad = UINT32_MAX;
  std::size_t b = 0;
  for (; b + kLanes <= count; b += kLanes) {
    std::uint32_t ii[kLanes], jj[kLanes];
    std::uint8_t images[kLanes];
    for (std::size_t l = 0; l < kLanes; ++l) {
      const std::uint32_t k = pairs[b + l];
      if (b + l + kPartnerAhead < count) {
        const std::uint32_t ahead = q.i[pairs[b + l + kPartnerAhead]];
        __builtin_prefetch(kin + kKinStride * ahead);
        __builtin_prefetch(kin + kKinStride * ahead + kKinStride - 1);
      }
      ii[l] = q.i[k];
      jj[l] = q.j[k];
      images[l] = q.image[k];
    }
    PairInputs<Lanes> in = pack_eight<kRolling>(kin, q, ii, jj, images);
    for (std::size_t l = 0; l < kLanes; ++l) {
      const std::uint32_t k = pairs[b + l];
      set_lane(in.m_star, l, q.m_star[k]);
      set_lane(in.inv_kt, l, q.inv_kt[k]);
      set_lane(in.hx, l, q.hx[k]);
      set_lane(in.hy, l, q.hy[k]);
      set_lane(in.hz, l, q.hz[k]);
    }
    store_outputs<kRolling>(blk, b, pair_law<kRolling, kClamp>(c, dt, in), false, 0, unused_large,
                            unused_bad);
  }
  for (; b < count; ++b) {
    PairInputs<double> in = pack_one<kRolling>(kin, q, pairs[b]);
    store_outputs<kRolling>(blk, b, pair_law<kRolling, kClamp>(c, dt, in), false, 0, unused_large,
                            unused_bad);
  }
}

}  // CONTACTLAB_DEM_ISA_NAMESPACE(build)
}  // namespace contactlab::dem::detail

#endif
