// The per-particle passes of a step (private to src/), eight particles at a time with the
// kinematics blocks and sums transposed in registers (vector loads and stores on the particle
// arrays, the force's sqrt on all lanes; a call per particle reloaded every array pointer):
// the drift (first half kick, move, the kinematics blocks the pair pass reads) and the finish
// (the summed contact force and torque, gravity and drag, the final half kick). Every lane
// does what the scalar tail does, in the same order, so where a range starts (it moves with
// the thread count) changes no bit.
#pragma once

#include <algorithm>
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

// Finishes particles [first, last), after their walls are in their sums (acc: kAccStride
// doubles a particle: force, torque, touching contacts).
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

struct DriftTerms {
  double dt, half_dt;    // [s]
  double kick;           // the velocities the forces see: v + a kick [s] (0: the half-step ones)
  double move_limit_sq;  // (skin/2)^2 [m^2]: a longer move in one step fails the run
};

// Drifts particles [first, last): v += a dt/2, x += v dt, their kinematics blocks rewritten
// (position, radius, the velocities the forces see, mass); max_disp_sq rises to the largest
// squared displacement since the last list build, bad falls to the first particle that moved
// more than the limit or whose position is not finite.
inline void drift_particles(Particles& p, double* kin, const DriftTerms& t, std::size_t first,
                            std::size_t last, double& max_disp_sq, std::uint32_t& bad) {
  double* __restrict x = p.x.data();
  double* __restrict y = p.y.data();
  double* __restrict z = p.z.data();
  double* __restrict vx = p.vx.data();
  double* __restrict vy = p.vy.data();
  double* __restrict vz = p.vz.data();
  double* __restrict wx = p.wx.data();
  double* __restrict wy = p.wy.data();
  double* __restrict wz = p.wz.data();
  const double* __restrict fx = p.fx.data();
  const double* __restrict fy = p.fy.data();
  const double* __restrict fz = p.fz.data();
  const double* __restrict tx = p.tx.data();
  const double* __restrict ty = p.ty.data();
  const double* __restrict tz = p.tz.data();
  const double* __restrict inv_mass = p.inv_mass.data();
  const double* __restrict inv_inertia = p.inv_inertia.data();
  const double* __restrict radius = p.radius.data();
  const double* __restrict mass = p.mass.data();
  const double* __restrict x0 = p.x0.data();
  const double* __restrict y0 = p.y0.data();
  const double* __restrict z0 = p.z0.data();
  const double dt = t.dt, half = t.half_dt, kick = t.kick, limit = t.move_limit_sq;
  std::size_t a = first;
  Lanes disp_max{};
  for (; a + kLanes <= last; a += kLanes) {
    const Lanes im = load_lanes(inv_mass + a), ii = load_lanes(inv_inertia + a);
    const Lanes ax = load_lanes(fx + a) * im, ay = load_lanes(fy + a) * im,
                az = load_lanes(fz + a) * im;
    const Lanes bx = load_lanes(tx + a) * ii, by = load_lanes(ty + a) * ii,
                bz = load_lanes(tz + a) * ii;
    const Lanes vxa = load_lanes(vx + a) + ax * half, vya = load_lanes(vy + a) + ay * half,
                vza = load_lanes(vz + a) + az * half;
    const Lanes wxa = load_lanes(wx + a) + bx * half, wya = load_lanes(wy + a) + by * half,
                wza = load_lanes(wz + a) + bz * half;
    store_lanes(vx + a, vxa);
    store_lanes(vy + a, vya);
    store_lanes(vz + a, vza);
    store_lanes(wx + a, wxa);
    store_lanes(wy + a, wya);
    store_lanes(wz + a, wza);
    const Lanes mx = vxa * dt, my = vya * dt, mz = vza * dt;
    const Lanes xa = load_lanes(x + a) + mx, ya = load_lanes(y + a) + my,
                za = load_lanes(z + a) + mz;
    store_lanes(x + a, xa);
    store_lanes(y + a, ya);
    store_lanes(z + a, za);
    // The kinematics blocks: x y z r pvx pvy pvz m as rows, then pwx pwy pwz 0.
    const Lanes head[kLanes] = {xa,
                                ya,
                                za,
                                load_lanes(radius + a),
                                vxa + ax * kick,
                                vya + ay * kick,
                                vza + az * kick,
                                load_lanes(mass + a)};
    const Lanes spin[kLanes] = {wxa + bx * kick, wya + by * kick, wza + bz * kick, Lanes{},
                                Lanes{},         Lanes{},         Lanes{},         Lanes{}};
    Lanes head_rows[kLanes], spin_rows[kLanes];
    transpose8(head, head_rows);
    transpose8(spin, spin_rows);
    for (std::size_t l = 0; l < kLanes; ++l) {
      double* block = kin + kKinStride * (a + l);
      store_lanes(block, head_rows[l]);
      std::memcpy(block + 8, &spin_rows[l], 4 * sizeof(double));
    }
    const Lanes ddx = xa - load_lanes(x0 + a), ddy = ya - load_lanes(y0 + a),
                ddz = za - load_lanes(z0 + a);
    const Lanes disp = ddx * ddx + ddy * ddy + ddz * ddz;
    disp_max = disp_max < disp ? disp : disp_max;
    const Lanes step_sq = mx * mx + my * my + mz * mz, sum = xa + ya + za;
    // x - x is 0 exactly when x is finite (inf - inf and NaN - NaN are NaN).
    if (any_false((step_sq <= limit) & (sum - sum == 0.0))) [[unlikely]] {
      for (std::size_t l = 0; l < kLanes; ++l) {
        if (!(step_sq[l] <= limit) || !std::isfinite(sum[l])) {
          bad = std::min(bad, static_cast<std::uint32_t>(a + l));
          break;
        }
      }
    }
  }
  for (std::size_t l = 0; l < kLanes; ++l) max_disp_sq = std::max(max_disp_sq, disp_max[l]);
  for (; a < last; ++a) {
    const double ax = fx[a] * inv_mass[a], ay = fy[a] * inv_mass[a], az = fz[a] * inv_mass[a];
    const double bx = tx[a] * inv_inertia[a], by = ty[a] * inv_inertia[a],
                 bz = tz[a] * inv_inertia[a];
    vx[a] += ax * half;
    vy[a] += ay * half;
    vz[a] += az * half;
    wx[a] += bx * half;
    wy[a] += by * half;
    wz[a] += bz * half;
    const double mx = vx[a] * dt, my = vy[a] * dt, mz = vz[a] * dt;
    x[a] += mx;
    y[a] += my;
    z[a] += mz;
    double* block = kin + kKinStride * a;
    block[0] = x[a];
    block[1] = y[a];
    block[2] = z[a];
    block[3] = radius[a];
    block[4] = vx[a] + ax * kick;
    block[5] = vy[a] + ay * kick;
    block[6] = vz[a] + az * kick;
    block[7] = mass[a];
    block[8] = wx[a] + bx * kick;
    block[9] = wy[a] + by * kick;
    block[10] = wz[a] + bz * kick;
    block[11] = 0.0;
    const double ddx = x[a] - x0[a], ddy = y[a] - y0[a], ddz = z[a] - z0[a];
    max_disp_sq = std::max(max_disp_sq, ddx * ddx + ddy * ddy + ddz * ddz);
    const double step_sq = mx * mx + my * my + mz * mz;
    if (!(step_sq <= limit) || !std::isfinite(x[a] + y[a] + z[a])) {
      bad = std::min(bad, static_cast<std::uint32_t>(a));
    }
  }
}

}  // namespace contactlab::dem::detail

#pragma GCC diagnostic pop
