// Analytic walls (plane, cylinder seen from inside, cone, plate with a circular orifice) as
// the closest point of their surface to a sphere's centre; moved or removed at given times.
#pragma once

#include <array>
#include <limits>
#include <string>

namespace contactlab::dem {

using Vec3 = std::array<double, 3>;

enum class WallKind { kPlane, kCylinder, kCone, kOrificePlate };

struct Wall {
  WallKind kind = WallKind::kPlane;
  std::string name;
  Vec3 point{0, 0, 0};   // m: plane point; cylinder/cone axis point (cone: apex); plate centre
  Vec3 normal{0, 0, 1};  // plane normal (particles on its side) / cylinder, cone, plate axis
  double radius = 0.0;   // m: cylinder radius, orifice radius
  double half_angle_rad = 0.0;  // cone: angle between axis and surface
  // Cylinder and cone: the extent along the axis from `point` [m]; outside it no contact.
  double axial_min = -std::numeric_limits<double>::infinity();
  double axial_max = std::numeric_limits<double>::infinity();
  Vec3 velocity{0, 0, 0};  // m/s, while move_from_s <= t < move_until_s
  double move_from_s = 0.0;
  double move_until_s = 0.0;
  double remove_at_s = std::numeric_limits<double>::infinity();  // gone from this time on

  bool active(double t_s) const { return t_s < remove_at_s; }
  // The wall's translation at time t [m] and its velocity [m/s].
  Vec3 offset(double t_s) const;
  Vec3 velocity_at(double t_s) const;
};

// The point of the wall's surface closest to c at time t; false when the wall is inactive or
// has no surface point there (outside a cylinder's or cone's axial extent).
bool closest_point(const Wall& wall, double t_s, const Vec3& c, Vec3& out);

// Throws InputError naming the wall for a zero axis, radius <= 0, a cone angle outside
// (0, 90) degrees or an empty axial extent; normalises the axis.
void validate_wall(Wall& wall, const std::string& where);

}  // namespace contactlab::dem
