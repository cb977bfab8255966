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
  double *x, *y, *z, *vx, *vy, *vz, *wx, *wy, *wz;  // force and torque: ForceColumns
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

// Force and torque as columns, one double a particle: the particle arrays (first = 0), or a
// piece's buffer whose element 0 is particle `first`.
struct ForceColumns {
  double *fx, *fy, *fz, *tx, *ty, *tz;
  std::size_t first;
  static ForceColumns of(Particles& p) {
    return {p.fx.data(), p.fy.data(), p.fz.data(), p.tx.data(), p.ty.data(), p.tz.data(), 0};
  }
  // A buffer of 6 x count doubles for particles [first, first + count).
  static ForceColumns in(double* buffer, std::size_t count, std::size_t first) {
    return {buffer,
            buffer + count,
            buffer + 2 * count,
            buffer + 3 * count,
            buffer + 4 * count,
            buffer + 5 * count,
            first};
  }
};

// Where a finish puts a particle's results. To the particle arrays: force and torque, |F| of
// the contacts and their count. Or, in a step whose finish drifts the next one (run_steps),
// back into the particle's sums, in place (force, torque, count, |F|: the sums' lines are
// written this step anyway, where the arrays were 116 more bytes a particle to and from
// memory: 4 - 7 % of the bed's step on a Xeon with AVX-512), with force and torque also to
// `columns` (a piece's buffer in L1) for the drift; Engine::store_forces copies the sums to
// the arrays where anything reads them (a rebuild, a failed step).
struct FinishOut {
  ForceColumns columns;
  bool to_sums;
};

// Finishes particles [first, last), after their walls are in their sums (acc: kAccStride
// doubles a particle: force, torque, touching contacts), their results where `out` says.
inline void finish_particles(const double* kin, double* acc, Particles& p, const FinishTerms& t,
                             std::size_t first, std::size_t last, const FinishOut& out) {
  const ParticleArrays arrays(p);
  const ForceColumns& f = out.columns;
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
    Lanes fx = s[0], fy = s[1], fz = s[2];
    const Lanes magnitude = sqrt_lanes(fx * fx + fy * fy + fz * fz);
    if (!out.to_sums) {
      store_counts(arrays.contacts + a, s[6]);  // exact: sums of ones
      store_lanes(arrays.force_magnitude + a, magnitude);
    }
    fx -= drag * pvx;
    fy -= drag * pvy;
    fz -= drag * pvz;
    fx += mass * gx;
    fy += mass * gy;
    fz += mass * gz;
    const std::size_t c = a - f.first;
    store_lanes(f.fx + c, fx);
    store_lanes(f.fy + c, fy);
    store_lanes(f.fz + c, fz);
    store_lanes(f.tx + c, s[3]);
    store_lanes(f.ty + c, s[4]);
    store_lanes(f.tz + c, s[5]);
    if (out.to_sums) {
      const Lanes results[kLanes] = {fx, fy, fz, s[3], s[4], s[5], s[6], magnitude};
      store_transposed(results, acc + kAccStride * a, kAccStride);
    }
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
    double* sum = acc + kAccStride * a;
    double fx = sum[0], fy = sum[1], fz = sum[2];
    const double tx = sum[3], ty = sum[4], tz = sum[5];
    const double magnitude = std::sqrt(fx * fx + fy * fy + fz * fz);
    if (!out.to_sums) {
      arrays.contacts[a] = static_cast<std::uint16_t>(sum[6]);
      arrays.force_magnitude[a] = magnitude;
    }
    fx -= drag * ka[4];
    fy -= drag * ka[5];
    fz -= drag * ka[6];
    fx += ka[7] * gx;
    fy += ka[7] * gy;
    fz += ka[7] * gz;
    const std::size_t c = a - f.first;
    f.fx[c] = fx;
    f.fy[c] = fy;
    f.fz[c] = fz;
    f.tx[c] = tx;
    f.ty[c] = ty;
    f.tz[c] = tz;
    if (out.to_sums) {
      sum[0] = fx;
      sum[1] = fy;
      sum[2] = fz;
      sum[7] = magnitude;  // torque and count stay where they are
    }
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
  // Bit p % 8 of byte p / 8 set: particle p is left out of max_step_sq (a hot particle of the
  // near pairs, whose every pair is near: NearPairs::hot). Null: none is.
  const std::uint8_t* hot = nullptr;
};

// The hot bits of particles [a, a + 8) as one byte (`hot` holds a byte past the last
// particle's).
[[gnu::always_inline]] inline unsigned hot_byte(const std::uint8_t* hot, std::size_t a) {
  const unsigned two = hot[a / 8] | static_cast<unsigned>(hot[a / 8 + 1]) << 8;
  return (two >> (a % 8)) & 0xFFu;
}

// Drifts particles [first, last): v += a dt/2, x += v dt, their kinematics blocks rewritten
// (position, radius, the velocities the forces see, mass); max_disp_sq rises to the largest
// squared displacement since the last list build, max_step_sq to the largest squared move of
// this step (of the particles not hot), bad falls to the first particle that moved more than
// the limit or whose position is not finite.
// Force and torque come from `forces` (the arrays, or the finish's piece buffer).
inline void drift_particles(Particles& p, double* kin, const DriftTerms& t,
                            const ForceColumns& forces, std::size_t first, std::size_t last,
                            double& max_disp_sq, double& max_step_sq, std::uint32_t& bad) {
  const ParticleArrays arrays(p);
  const ForceColumns& f = forces;
  const double dt = t.dt, half = t.half_dt, kick = t.kick, limit = t.move_limit_sq;
  std::size_t a = first;
  Lanes disp_max{}, step_max{};
  for (; a + kLanes <= last; a += kLanes) {
    const Lanes im = load_lanes(arrays.inv_mass + a), ii = load_lanes(arrays.inv_inertia + a);
    const std::size_t c = a - f.first;
    const Lanes ax = load_lanes(f.fx + c) * im, ay = load_lanes(f.fy + c) * im,
                az = load_lanes(f.fz + c) * im;
    const Lanes bx = load_lanes(f.tx + c) * ii, by = load_lanes(f.ty + c) * ii,
                bz = load_lanes(f.tz + c) * ii;
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
    const unsigned hot = t.hot == nullptr ? 0u : hot_byte(t.hot, a);
    if (hot == 0) [[likely]] {
      step_max = select(step_max < step_sq, step_sq, step_max);
    } else {  // a few in a hundred groups
      for (std::size_t l = 0; l < kLanes; ++l) {
        if (((hot >> l) & 1u) == 0) max_step_sq = std::max(max_step_sq, step_sq[l]);
      }
    }
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
  for (std::size_t l = 0; l < kLanes; ++l) {
    max_disp_sq = std::max(max_disp_sq, disp_max[l]);
    max_step_sq = std::max(max_step_sq, step_max[l]);
  }
  for (; a < last; ++a) {
    const std::size_t c = a - f.first;
    const double ax = f.fx[c] * arrays.inv_mass[a], ay = f.fy[c] * arrays.inv_mass[a],
                 az = f.fz[c] * arrays.inv_mass[a];
    const double bx = f.tx[c] * arrays.inv_inertia[a], by = f.ty[c] * arrays.inv_inertia[a],
                 bz = f.tz[c] * arrays.inv_inertia[a];
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
    if (t.hot == nullptr || ((t.hot[a / 8] >> (a % 8)) & 1u) == 0) {
      max_step_sq = std::max(max_step_sq, step_sq);
    }
    if (!(step_sq <= limit) || !std::isfinite(arrays.x[a] + arrays.y[a] + arrays.z[a])) {
      bad = std::min(bad, static_cast<std::uint32_t>(a));
    }
  }
}

}  // CONTACTLAB_DEM_ISA_NAMESPACE(build)
}  // namespace contactlab::dem::detail

#endif
