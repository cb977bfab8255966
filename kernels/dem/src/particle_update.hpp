// The per-particle passes of a step (private to src/), eight particles at a time with the
// kinematics blocks and sums transposed in registers (vector loads and stores on the particle
// arrays, the force's sqrt on all lanes; a call per particle reloaded every array pointer):
// the drift (first half kick, move, the kinematics blocks the pair pass reads) and the finish
// (the summed contact force and torque, gravity and drag, the final half kick). Every lane
// does what the scalar tail does, in the same order, so where a range starts (it moves with
// the thread count) changes no bit.
// Compiled once per instruction set (dem_isa.hpp): a toggle, no include guard.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>

#include "contactlab/dem/particles.hpp"
#include "dem_isa.hpp"
#include "kin_columns.hpp"
#include "lanes.hpp"
#include "pair_block.hpp"

#if defined(CONTACTLAB_DEM_PARTICLE_UPDATE_TOGGLE) == defined(CONTACTLAB_DEM_ISA_TOGGLE)
#ifdef CONTACTLAB_DEM_PARTICLE_UPDATE_TOGGLE
#undef CONTACTLAB_DEM_PARTICLE_UPDATE_TOGGLE
#else
#define CONTACTLAB_DEM_PARTICLE_UPDATE_TOGGLE
#endif

namespace contactlab::dem::detail {
CONTACTLAB_DEM_ISA_NAMESPACE(build) {

// The particle arrays the passes read and write, as plain pointers held over a loop (a call
// per particle reloaded each from its vector).
struct ParticleArrays {
  double *x, *y, *z, *vx, *vy, *vz, *wx, *wy, *wz, *fx, *fy, *fz, *tx, *ty, *tz;
  double* force_magnitude;
  std::uint16_t* contacts;
  const double *inv_mass, *inv_inertia, *radius, *mass, *x0, *y0, *z0;
  explicit ParticleArrays(Particles& p)
      : x(p.x.data()),
        y(p.y.data()),
        z(p.z.data()),
        vx(p.vx.data()),
        vy(p.vy.data()),
        vz(p.vz.data()),
        wx(p.wx.data()),
        wy(p.wy.data()),
        wz(p.wz.data()),
        fx(p.fx.data()),
        fy(p.fy.data()),
        fz(p.fz.data()),
        tx(p.tx.data()),
        ty(p.ty.data()),
        tz(p.tz.data()),
        force_magnitude(p.force_magnitude.data()),
        contacts(p.contacts.data()),
        inv_mass(p.inv_mass.data()),
        inv_inertia(p.inv_inertia.data()),
        radius(p.radius.data()),
        mass(p.mass.data()),
        x0(p.x0.data()),
        y0(p.y0.data()),
        z0(p.z0.data()) {}
};

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
  const ParticleArrays arrays(p);
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
    store_counts(arrays.contacts + a, s[6]);  // exact: sums of ones
    Lanes fx = s[0], fy = s[1], fz = s[2];
    store_lanes(arrays.force_magnitude + a, sqrt_lanes(fx * fx + fy * fy + fz * fz));
    fx -= drag * pvx;
    fy -= drag * pvy;
    fz -= drag * pvz;
    fx += mass * gx;
    fy += mass * gy;
    fz += mass * gz;
    store_lanes(arrays.fx + a, fx);
    store_lanes(arrays.fy + a, fy);
    store_lanes(arrays.fz + a, fz);
    store_lanes(arrays.tx + a, s[3]);
    store_lanes(arrays.ty + a, s[4]);
    store_lanes(arrays.tz + a, s[5]);
    if (t.kick) {
      const Lanes im = load_lanes(arrays.inv_mass + a), ii = load_lanes(arrays.inv_inertia + a);
      store_lanes(arrays.vx + a, load_lanes(arrays.vx + a) + fx * im * half);
      store_lanes(arrays.vy + a, load_lanes(arrays.vy + a) + fy * im * half);
      store_lanes(arrays.vz + a, load_lanes(arrays.vz + a) + fz * im * half);
      store_lanes(arrays.wx + a, load_lanes(arrays.wx + a) + s[3] * ii * half);
      store_lanes(arrays.wy + a, load_lanes(arrays.wy + a) + s[4] * ii * half);
      store_lanes(arrays.wz + a, load_lanes(arrays.wz + a) + s[5] * ii * half);
    }
  }
  for (; a < last; ++a) {
    const double* ka = kin + kKinStride * a;
    const double* sum = acc + kAccStride * a;
    double fx = sum[0], fy = sum[1], fz = sum[2];
    const double tx = sum[3], ty = sum[4], tz = sum[5];
    arrays.contacts[a] = static_cast<std::uint16_t>(sum[6]);
    arrays.force_magnitude[a] = std::sqrt(fx * fx + fy * fy + fz * fz);
    fx -= drag * ka[4];
    fy -= drag * ka[5];
    fz -= drag * ka[6];
    fx += ka[7] * gx;
    fy += ka[7] * gy;
    fz += ka[7] * gz;
    arrays.fx[a] = fx;
    arrays.fy[a] = fy;
    arrays.fz[a] = fz;
    arrays.tx[a] = tx;
    arrays.ty[a] = ty;
    arrays.tz[a] = tz;
    if (t.kick) {
      arrays.vx[a] += fx * arrays.inv_mass[a] * half;
      arrays.vy[a] += fy * arrays.inv_mass[a] * half;
      arrays.vz[a] += fz * arrays.inv_mass[a] * half;
      arrays.wx[a] += tx * arrays.inv_inertia[a] * half;
      arrays.wy[a] += ty * arrays.inv_inertia[a] * half;
      arrays.wz[a] += tz * arrays.inv_inertia[a] * half;
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
  const ParticleArrays arrays(p);
  const double dt = t.dt, half = t.half_dt, kick = t.kick, limit = t.move_limit_sq;
  std::size_t a = first;
  Lanes disp_max{};
  for (; a + kLanes <= last; a += kLanes) {
    const Lanes im = load_lanes(arrays.inv_mass + a), ii = load_lanes(arrays.inv_inertia + a);
    const Lanes ax = load_lanes(arrays.fx + a) * im, ay = load_lanes(arrays.fy + a) * im,
                az = load_lanes(arrays.fz + a) * im;
    const Lanes bx = load_lanes(arrays.tx + a) * ii, by = load_lanes(arrays.ty + a) * ii,
                bz = load_lanes(arrays.tz + a) * ii;
    const Lanes vxa = load_lanes(arrays.vx + a) + ax * half,
                vya = load_lanes(arrays.vy + a) + ay * half,
                vza = load_lanes(arrays.vz + a) + az * half;
    const Lanes wxa = load_lanes(arrays.wx + a) + bx * half,
                wya = load_lanes(arrays.wy + a) + by * half,
                wza = load_lanes(arrays.wz + a) + bz * half;
    store_lanes(arrays.vx + a, vxa);
    store_lanes(arrays.vy + a, vya);
    store_lanes(arrays.vz + a, vza);
    store_lanes(arrays.wx + a, wxa);
    store_lanes(arrays.wy + a, wya);
    store_lanes(arrays.wz + a, wza);
    const Lanes mx = vxa * dt, my = vya * dt, mz = vza * dt;
    const Lanes xa = load_lanes(arrays.x + a) + mx, ya = load_lanes(arrays.y + a) + my,
                za = load_lanes(arrays.z + a) + mz;
    store_lanes(arrays.x + a, xa);
    store_lanes(arrays.y + a, ya);
    store_lanes(arrays.z + a, za);
    // The kinematics blocks: x y z r pvx pvy pvz m as rows, then pwx pwy pwz 0.
    const Lanes head[kLanes] = {xa,
                                ya,
                                za,
                                load_lanes(arrays.radius + a),
                                vxa + ax * kick,
                                vya + ay * kick,
                                vza + az * kick,
                                load_lanes(arrays.mass + a)};
    const Lanes spin[kLanes] = {wxa + bx * kick, wya + by * kick, wza + bz * kick, Lanes{},
                                Lanes{},         Lanes{},         Lanes{},         Lanes{}};
    store_transposed(head, kin + kKinStride * a, kKinStride);
    store_transposed<kLanes / 2>(spin, kin + kKinStride * a + 8, kKinStride);
    const Lanes ddx = xa - load_lanes(arrays.x0 + a), ddy = ya - load_lanes(arrays.y0 + a),
                ddz = za - load_lanes(arrays.z0 + a);
    const Lanes disp = ddx * ddx + ddy * ddy + ddz * ddz;
    disp_max = select(disp_max < disp, disp, disp_max);
    const Lanes step_sq = mx * mx + my * my + mz * mz, sum = xa + ya + za;
    // x - x is 0 exactly when x is finite (inf - inf and NaN - NaN are NaN).
    // NOLINTNEXTLINE(misc-redundant-expression): that finiteness test, on purpose
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
    const double ax = arrays.fx[a] * arrays.inv_mass[a], ay = arrays.fy[a] * arrays.inv_mass[a],
                 az = arrays.fz[a] * arrays.inv_mass[a];
    const double bx = arrays.tx[a] * arrays.inv_inertia[a],
                 by = arrays.ty[a] * arrays.inv_inertia[a],
                 bz = arrays.tz[a] * arrays.inv_inertia[a];
    arrays.vx[a] += ax * half;
    arrays.vy[a] += ay * half;
    arrays.vz[a] += az * half;
    arrays.wx[a] += bx * half;
    arrays.wy[a] += by * half;
    arrays.wz[a] += bz * half;
    const double mx = arrays.vx[a] * dt, my = arrays.vy[a] * dt, mz = arrays.vz[a] * dt;
    arrays.x[a] += mx;
    arrays.y[a] += my;
    arrays.z[a] += mz;
    double* block = kin + kKinStride * a;
    block[0] = arrays.x[a];
    block[1] = arrays.y[a];
    block[2] = arrays.z[a];
    block[3] = arrays.radius[a];
    block[4] = arrays.vx[a] + ax * kick;
    block[5] = arrays.vy[a] + ay * kick;
    block[6] = arrays.vz[a] + az * kick;
    block[7] = arrays.mass[a];
    block[8] = arrays.wx[a] + bx * kick;
    block[9] = arrays.wy[a] + by * kick;
    block[10] = arrays.wz[a] + bz * kick;
    block[11] = 0.0;
    const double ddx = arrays.x[a] - arrays.x0[a], ddy = arrays.y[a] - arrays.y0[a],
                 ddz = arrays.z[a] - arrays.z0[a];
    max_disp_sq = std::max(max_disp_sq, ddx * ddx + ddy * ddy + ddz * ddz);
    const double step_sq = mx * mx + my * my + mz * mz;
    if (!(step_sq <= limit) || !std::isfinite(arrays.x[a] + arrays.y[a] + arrays.z[a])) {
      bad = std::min(bad, static_cast<std::uint32_t>(a));
    }
  }
}

}  // CONTACTLAB_DEM_ISA_NAMESPACE(build)
}  // namespace contactlab::dem::detail

#endif
