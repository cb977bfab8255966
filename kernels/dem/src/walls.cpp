// Closest surface points of the analytic walls.
#include "contactlab/dem/walls.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "contactlab/kernels/error.hpp"

namespace contactlab::dem {
namespace {

double dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

}  // namespace

Vec3 Wall::offset(double t_s) const {
  const double moved =
      std::clamp(t_s, move_from_s, std::max(move_from_s, move_until_s)) - move_from_s;
  return {velocity[0] * moved, velocity[1] * moved, velocity[2] * moved};
}

Vec3 Wall::velocity_at(double t_s) const {
  if (t_s >= move_from_s && t_s < move_until_s) return velocity;
  return {0, 0, 0};
}

bool closest_point(const Wall& wall, double t_s, const Vec3& c, Vec3& out) {
  if (!wall.active(t_s)) return false;
  const Vec3 shift = wall.offset(t_s);
  const Vec3 p{wall.point[0] + shift[0], wall.point[1] + shift[1], wall.point[2] + shift[2]};
  const Vec3& a = wall.normal;
  const Vec3 r{c[0] - p[0], c[1] - p[1], c[2] - p[2]};
  const double along = dot(r, a);
  if (wall.kind == WallKind::kPlane) {  // the common case: no radial direction needed
    out = {c[0] - along * a[0], c[1] - along * a[1], c[2] - along * a[2]};
    return true;
  }
  const Vec3 radial{r[0] - along * a[0], r[1] - along * a[1], r[2] - along * a[2]};
  const double rho = std::sqrt(dot(radial, radial));
  // A unit radial direction (any one on the axis itself).
  Vec3 u{0, 0, 0};
  if (rho > 0) {
    u = {radial[0] / rho, radial[1] / rho, radial[2] / rho};
  } else {
    const Vec3 t = std::abs(a[0]) < 0.9 ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
    const double ta = dot(t, a);
    const Vec3 v{t[0] - ta * a[0], t[1] - ta * a[1], t[2] - ta * a[2]};
    const double nv = std::sqrt(dot(v, v));
    u = {v[0] / nv, v[1] / nv, v[2] / nv};
  }
  switch (wall.kind) {
    case WallKind::kPlane:
      return true;  // handled above
    case WallKind::kCylinder: {
      if (along < wall.axial_min || along > wall.axial_max) return false;
      for (int k = 0; k < 3; ++k) out[k] = p[k] + along * a[k] + wall.radius * u[k];
      return true;
    }
    case WallKind::kCone: {
      // In the (axis, radial) half-plane the surface is the ray s (cos a, sin a), s >= 0.
      const double ca = std::cos(wall.half_angle_rad), sa = std::sin(wall.half_angle_rad);
      const double s_lo = std::max(0.0, wall.axial_min / ca), s_hi = wall.axial_max / ca;
      const double s = std::clamp(along * ca + rho * sa, s_lo, s_hi);
      for (int k = 0; k < 3; ++k) out[k] = p[k] + s * ca * a[k] + s * sa * u[k];
      return true;
    }
    case WallKind::kOrificePlate: {
      // The face where the foot of c lies on the plate, else the rim edge (the hole's circle).
      const double foot = std::max(rho, wall.radius);
      for (int k = 0; k < 3; ++k) out[k] = p[k] + foot * u[k];
      return true;
    }
  }
  return false;
}

void validate_wall(Wall& wall, const std::string& where) {
  const double n = std::sqrt(dot(wall.normal, wall.normal));
  if (!(n > 0) || !std::isfinite(n)) throw InputError(where + ": axis/normal must be non-zero");
  for (double& v : wall.normal) v /= n;
  if ((wall.kind == WallKind::kCylinder || wall.kind == WallKind::kOrificePlate) &&
      !(wall.radius > 0)) {
    throw InputError(where + ": radius must be > 0 m (got " + number_text(wall.radius) + ")");
  }
  if (wall.kind == WallKind::kCone &&
      !(wall.half_angle_rad > 0 && wall.half_angle_rad < std::numbers::pi / 2)) {
    throw InputError(where + ": half_angle must be in (0, 90) degrees");
  }
  if (!(wall.axial_min < wall.axial_max)) {
    throw InputError(where + ": axial_min must be < axial_max");
  }
  if (wall.move_until_s < wall.move_from_s) {
    throw InputError(where + ": move_until must be >= move_from");
  }
}

}  // namespace contactlab::dem
