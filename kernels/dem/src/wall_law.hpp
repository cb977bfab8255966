// The contact law of a particle against the walls (private to src/): the pair law of
// pair_block.hpp with the wall as a partner of infinite mass and zero radius (reduced mass = the
// particle's), its tangential spring kept per particle and wall. The walls' positions,
// velocities and whether they still act are taken once per step; a particle's contacts are
// then added to its force and torque sums by the force pass's finish.
// Compiled once per instruction set (dem_isa.hpp): a toggle, no include guard.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "contactlab/dem/contact_law.hpp"
#include "contactlab/dem/particles.hpp"
#include "contactlab/dem/walls.hpp"
#include "dem_isa.hpp"
#include "pair_block.hpp"

#if defined(CONTACTLAB_DEM_WALL_LAW_TOGGLE) == defined(CONTACTLAB_DEM_ISA_TOGGLE)
#ifdef CONTACTLAB_DEM_WALL_LAW_TOGGLE
#undef CONTACTLAB_DEM_WALL_LAW_TOGGLE
#else
#define CONTACTLAB_DEM_WALL_LAW_TOGGLE
#endif

namespace contactlab::dem::detail {
CONTACTLAB_DEM_ISA_NAMESPACE(build) {

class WallLaw {
 public:
  WallLaw(const std::vector<Wall>& walls, double time_s, const PairCoefficients& c, double dt)
      : walls_(walls), time_s_(time_s), c_(c), dt_(dt), rolling_(c.mu_roll > 0) {
    const std::size_t count = walls.size();
    point_.resize(count);
    velocity_.resize(count);
    plane_.resize(count);
    active_.resize(count);
    for (std::size_t w = 0; w < count; ++w) {
      const Wall& wall = walls[w];
      velocity_[w] = wall.velocity_at(time_s);
      const Vec3 shift = wall.offset(time_s);
      for (int k = 0; k < 3; ++k) point_[w][k] = wall.point[k] + shift[k];
      plane_[w] = wall.kind == WallKind::kPlane;
      active_[w] = wall.active(time_s);
    }
  }

  // Particle a's wall contacts added to sum (force, torque, touching: kAccStride doubles).
  // `reach` has bit w set where wall w < 32 may touch a (the others are always tried); ka is a's
  // kinematics block (position, radius, mass and synchronised velocities: the same values as
  // the particle arrays); the springs are p.wall_spring. Overlaps past kWarnFraction of the
  // radius count in `large`, past kFailFraction the smallest such particle goes to `bad`.
  void add(std::size_t a, std::uint32_t reach, const double* ka, Particles& p, double* sum,
           std::uint64_t& large, std::uint32_t& bad) const {
    const std::size_t count = walls_.size();
    // Most particles of a scene reach no wall: skip them before loading anything else.
    if (reach == 0 && count <= 32) return;
    const double xa = ka[0], ya = ka[1], za = ka[2], r = ka[3], mass = ka[7];
    const double pvxa = ka[4], pvya = ka[5], pvza = ka[6], pwxa = ka[8], pwya = ka[9],
                 pwza = ka[10];
    for (std::size_t w = 0; w < count; ++w) {
      if (w < 32 && ((reach >> w) & 1u) == 0) continue;  // out of reach (its spring is zero)
      double* hx = &p.wall_spring[3 * w][a];
      double* hy = &p.wall_spring[3 * w + 1][a];
      double* hz = &p.wall_spring[3 * w + 2][a];
      double dx, dy, dz;
      bool any = active_[w];
      if (plane_[w]) {  // inline: the distance along the normal, no closest point
        const Vec3& o = point_[w];
        const Vec3& nn = walls_[w].normal;
        const double along = (xa - o[0]) * nn[0] + (ya - o[1]) * nn[1] + (za - o[2]) * nn[2];
        dx = along * nn[0];
        dy = along * nn[1];
        dz = along * nn[2];
      } else {
        Vec3 cp{};
        any = closest_point(walls_[w], time_s_, {xa, ya, za}, cp);
        dx = xa - cp[0];
        dy = ya - cp[1];
        dz = za - cp[2];
      }
      const double rsq = dx * dx + dy * dy + dz * dz;
      if (!any || rsq >= r * r || rsq == 0.0) {
        *hx = *hy = *hz = 0.0;
        continue;
      }
      const double dist = std::sqrt(rsq), inv = 1.0 / dist;
      const double nx = dx * inv, ny = dy * inv, nz = dz * inv;
      const double delta = r - dist;
      large += delta > kWarnFraction * r;
      if (delta > kFailFraction * r) bad = std::min(bad, static_cast<std::uint32_t>(a));
      const double m_star = mass;
      const Vec3& wv = velocity_[w];
      const double sx = r * pwxa, sy = r * pwya, sz = r * pwza;
      const double vx = pvxa - wv[0] - (sy * nz - sz * ny);
      const double vy = pvya - wv[1] - (sz * nx - sx * nz);
      const double vz = pvza - wv[2] - (sx * ny - sy * nx);
      const double vn = vx * nx + vy * ny + vz * nz;
      const double kn = c_.k_abs + c_.k_per_mass * m_star, cn = c_.c_per_mass * m_star;
      double fn = kn * delta - cn * vn;
      if (c_.clamp) fn = std::max(fn, 0.0);
      const Tangential<double> ft =
          tangential(nx, ny, nz, vx - vn * nx, vy - vn * ny, vz - vn * nz, fn, c_.kt_ratio * kn,
                     inverse_kt(c_, m_star), c_.ct_ratio * cn, c_.mu, dt_, *hx, *hy, *hz);
      sum[0] += fn * nx + ft.ftx;
      sum[1] += fn * ny + ft.fty;
      sum[2] += fn * nz + ft.ftz;
      sum[3] -= r * (ny * ft.ftz - nz * ft.fty);
      sum[4] -= r * (nz * ft.ftx - nx * ft.ftz);
      sum[5] -= r * (nx * ft.fty - ny * ft.ftx);
      if (rolling_) {
        const double om = std::sqrt(pwxa * pwxa + pwya * pwya + pwza * pwza);
        const double s = om > 0 ? -c_.mu_roll * fn * r / om : 0.0;
        sum[3] += s * pwxa;
        sum[4] += s * pwya;
        sum[5] += s * pwza;
      }
      sum[6] += fn > 0;
    }
  }

 private:
  const std::vector<Wall>& walls_;
  double time_s_;
  const PairCoefficients& c_;
  double dt_;
  bool rolling_;
  std::vector<Vec3> point_, velocity_;        // where each wall is now, how fast it moves
  std::vector<std::uint8_t> plane_, active_;  // a plane (no closest point); still in place
};

}  // CONTACTLAB_DEM_ISA_NAMESPACE(build)
}  // namespace contactlab::dem::detail

#endif
