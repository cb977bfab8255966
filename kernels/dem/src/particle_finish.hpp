// The end of a force evaluation for a range of particles (private to src/): each particle's
// summed contact force and torque, gravity and drag, into the particle arrays, and the final
// half kick. Eight particles at a time: their kinematics blocks and sums are transposed in
// registers, so the arrays are written with vector stores and the force's sqrt runs on all
// lanes (a call per particle reloaded every array pointer and ran one sqrt at a time).
#pragma once

#include <cmath>
#include <cstdint>
#include <cstring>

#include "contactlab/dem/particles.hpp"
#include "kin_columns.hpp"
#include "pair_block.hpp"

// 64-byte vectors without AVX-512: see kin_columns.hpp.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wpsabi"

namespace contactlab::dem::detail {

struct FinishTerms {
  double drag;        // background drag coefficient [kg/s] (settling only)
  double gravity[3];  // [m/s^2]
  double half_dt;     // [s]
  bool kick;          // apply the final half kick
};

// Particles [first, last), after their walls are in their sums (acc: kAccStride doubles a
// particle: force, torque, touching contacts). Every lane does what the scalar tail does, in
// the same order, so where a range starts (it moves with the thread count) changes no bit.
inline void finish_particles(const double* kin, const double* acc, Particles& p,
                             const FinishTerms& t, std::size_t first, std::size_t last) {
  std::uint16_t* __restrict contacts = p.contacts.data();
  double* __restrict magnitude = p.force_magnitude.data();
  double* __restrict fx_out = p.fx.data();
  double* __restrict fy_out = p.fy.data();
  double* __restrict fz_out = p.fz.data();
  double* __restrict tx_out = p.tx.data();
  double* __restrict ty_out = p.ty.data();
  double* __restrict tz_out = p.tz.data();
  double* __restrict vx = p.vx.data();
  double* __restrict vy = p.vy.data();
  double* __restrict vz = p.vz.data();
  double* __restrict wx = p.wx.data();
  double* __restrict wy = p.wy.data();
  double* __restrict wz = p.wz.data();
  const double* __restrict inv_mass = p.inv_mass.data();
  const double* __restrict inv_inertia = p.inv_inertia.data();
  const double drag = t.drag, gx = t.gravity[0], gy = t.gravity[1], gz = t.gravity[2];
  const double half = t.half_dt;
  std::size_t a = first;
  for (; a + kLanes <= last; a += kLanes) {
    Lanes kin_rows[kLanes], sum_rows[kLanes], s[kLanes];
    for (std::size_t l = 0; l < kLanes; ++l) {
      kin_rows[l] = load_lanes(kin + kKinStride * (a + l));
      sum_rows[l] = load_lanes(acc + kAccStride * (a + l));
    }
    Lanes pvx, pvy, pvz, mass;  // the synchronised velocity and the mass: lanes 4..7 of kin
    top_columns(kin_rows, pvx, pvy, pvz, mass);
    transpose8(sum_rows, s);
    using Counts = std::uint16_t __attribute__((vector_size(2 * kLanes)));
    const Counts touching = __builtin_convertvector(s[6], Counts);  // exact: sums of ones
    std::memcpy(contacts + a, &touching, sizeof touching);
    Lanes fx = s[0], fy = s[1], fz = s[2];
    store_lanes(magnitude + a, sqrt_lanes(fx * fx + fy * fy + fz * fz));
    fx -= drag * pvx;
    fy -= drag * pvy;
    fz -= drag * pvz;
    fx += mass * gx;
    fy += mass * gy;
    fz += mass * gz;
    store_lanes(fx_out + a, fx);
    store_lanes(fy_out + a, fy);
    store_lanes(fz_out + a, fz);
    store_lanes(tx_out + a, s[3]);
    store_lanes(ty_out + a, s[4]);
    store_lanes(tz_out + a, s[5]);
    if (t.kick) {
      const Lanes im = load_lanes(inv_mass + a), ii = load_lanes(inv_inertia + a);
      store_lanes(vx + a, load_lanes(vx + a) + fx * im * half);
      store_lanes(vy + a, load_lanes(vy + a) + fy * im * half);
      store_lanes(vz + a, load_lanes(vz + a) + fz * im * half);
      store_lanes(wx + a, load_lanes(wx + a) + s[3] * ii * half);
      store_lanes(wy + a, load_lanes(wy + a) + s[4] * ii * half);
      store_lanes(wz + a, load_lanes(wz + a) + s[5] * ii * half);
    }
  }
  for (; a < last; ++a) {
    const double* ka = kin + kKinStride * a;
    const double* sum = acc + kAccStride * a;
    double fx = sum[0], fy = sum[1], fz = sum[2];
    const double tx = sum[3], ty = sum[4], tz = sum[5];
    contacts[a] = static_cast<std::uint16_t>(sum[6]);
    magnitude[a] = std::sqrt(fx * fx + fy * fy + fz * fz);
    fx -= drag * ka[4];
    fy -= drag * ka[5];
    fz -= drag * ka[6];
    fx += ka[7] * gx;
    fy += ka[7] * gy;
    fz += ka[7] * gz;
    fx_out[a] = fx;
    fy_out[a] = fy;
    fz_out[a] = fz;
    tx_out[a] = tx;
    ty_out[a] = ty;
    tz_out[a] = tz;
    if (t.kick) {
      vx[a] += fx * inv_mass[a] * half;
      vy[a] += fy * inv_mass[a] * half;
      vz[a] += fz * inv_mass[a] * half;
      wx[a] += tx * inv_inertia[a] * half;
      wy[a] += ty * inv_inertia[a] * half;
      wz[a] += tz * inv_inertia[a] * half;
    }
  }
}

}  // namespace contactlab::dem::detail

#pragma GCC diagnostic pop
