// Analytic walls: closest points of each shape (the orifice plate's face and rim edge), and
// walls that move or are removed at a given time.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "contactlab/dem/engine.hpp"
#include "contactlab/dem/walls.hpp"
#include "contactlab/kernels/error.hpp"

namespace contactlab::dem {
namespace {

Wall make(WallKind kind) {
  Wall w;  // unnamed: messages name it by the `where` given to validate_wall
  w.kind = kind;
  return w;
}

void expect_point(const Vec3& got, const Vec3& want) {
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(got[k], want[k], 1e-12) << "component " << k;
}

TEST(DemWalls, ClosestPoints) {
  Vec3 out{};
  Wall plane = make(WallKind::kPlane);
  plane.point = {0, 0, 1};
  validate_wall(plane, "plane");
  ASSERT_TRUE(closest_point(plane, 0.0, {0.3, -2, 1.5}, out));
  expect_point(out, {0.3, -2, 1});

  Wall cylinder = make(WallKind::kCylinder);
  cylinder.radius = 2;
  validate_wall(cylinder, "cylinder");
  ASSERT_TRUE(closest_point(cylinder, 0.0, {1, 0, 5}, out));
  expect_point(out, {2, 0, 5});

  // A cone opening upwards from the origin at 45 degrees: a point on the axis at height h is
  // h / sqrt(2) from the surface point (h/2, 0, h/2) (any azimuth; x chosen here by offset).
  Wall cone = make(WallKind::kCone);
  cone.half_angle_rad = std::numbers::pi / 4;
  validate_wall(cone, "cone");
  ASSERT_TRUE(closest_point(cone, 0.0, {1e-9, 0, 2}, out));
  EXPECT_NEAR(std::hypot(out[0], out[1]), 1.0, 1e-6);
  EXPECT_NEAR(out[2], 1.0, 1e-6);

  // Orifice plate at z = 0 with a hole of radius 1: beyond the hole the face, inside it the
  // rim edge.
  Wall plate = make(WallKind::kOrificePlate);
  plate.radius = 1;
  validate_wall(plate, "plate");
  ASSERT_TRUE(closest_point(plate, 0.0, {3, 0, 0.4}, out));
  expect_point(out, {3, 0, 0});
  ASSERT_TRUE(closest_point(plate, 0.0, {0.5, 0, 0.4}, out));
  expect_point(out, {1, 0, 0});
}

TEST(DemWalls, BadWallsAreRefused) {
  Wall cylinder = make(WallKind::kCylinder);
  EXPECT_THROW(validate_wall(cylinder, "$.walls[0]"), InputError);  // radius 0
  Wall cone = make(WallKind::kCone);
  cone.half_angle_rad = std::numbers::pi / 2;
  EXPECT_THROW(validate_wall(cone, "$.walls[1]"), InputError);
  Wall plane = make(WallKind::kPlane);
  plane.normal = {0, 0, 0};
  EXPECT_THROW(validate_wall(plane, "$.walls[2]"), InputError);
}

EngineSettings falling_settings() {
  EngineSettings s;
  s.law.restitution = 0.3;
  s.law.contact_time_s = 1e-4;
  s.law.friction = 0.3;
  s.gravity = {0, 0, -9.81};
  s.dt_s = 2e-6;
  s.domain.lo = {-1, -1, -1};
  s.domain.hi = {1, 1, 1};
  s.warn_large_overlaps = false;
  return s;
}

// A sphere resting on a plate's orifice rim (hole slightly narrower than the sphere) is held
// by the rim edge, and falls through once the plate is removed.
TEST(DemWalls, OrificeRimHoldsASphereUntilThePlateIsRemoved) {
  EngineSettings s = falling_settings();
  Wall plate = make(WallKind::kOrificePlate);
  plate.radius = 0.8e-3;  // sphere radius 1 mm: it rests in the hole, on the rim
  plate.remove_at_s = 0.02;
  validate_wall(plate, "plate");
  s.walls.push_back(plate);
  Particles p;
  p.add(0, 0, 0, 0, std::sqrt(1e-6 - 0.64e-6) + 1e-6, 1e-3, 2500);
  Engine engine(s, p);
  engine.run_steps(9000);  // 0.018 s: settled on the rim
  const double z_rim = engine.particles().z[0];
  EXPECT_NEAR(z_rim, std::sqrt(1e-6 - 0.64e-6), 2e-5);
  EXPECT_NEAR(engine.particles().vz[0], 0.0, 1e-3);
  engine.run_steps(6000);  // plate gone at 0.02 s: free fall for 0.01 s
  EXPECT_LT(engine.particles().vz[0], -0.05);
}

// A wall out of a particle's reach at a rebuild is not evaluated until the next one (the
// engine's wall reach): a sphere flying at a cylinder from its axis, many rebuilds away, still
// meets it and bounces back without a deep overlap (which would stop the run).
TEST(DemWalls, FarWallIsMetAfterManyRebuilds) {
  EngineSettings s = falling_settings();
  s.gravity = {0, 0, 0};
  Wall silo = make(WallKind::kCylinder);
  silo.radius = 10e-3;
  validate_wall(silo, "silo");
  s.walls.push_back(silo);
  Particles p;
  p.add(0, 0, 0, 0, 0, 1e-3, 2500);
  p.vx[0] = 3.0;  // 6 um a step: a rebuild every 17 steps (skin 0.2 mm)
  Engine engine(s, p);
  engine.run_steps(3000);  // the wall at 9 mm from the axis is met after 1500 steps
  EXPECT_GT(engine.rebuilds(), 50u);
  EXPECT_LT(engine.particles().vx[0], -0.5);  // bounced (e = 0.3)
  EXPECT_LT(engine.particles().x[0], 9e-3);
}

// A plane moving up at 0.1 m/s from t = 0.005 s to 0.015 s lifts a sphere resting on it (it
// bounces on the wall's sudden start); when the wall stops the sphere flies on and lands on it.
TEST(DemWalls, MovingWallCarriesASphere) {
  EngineSettings s = falling_settings();
  Wall floor = make(WallKind::kPlane);
  floor.velocity = {0, 0, 0.1};
  floor.move_from_s = 0.005;
  floor.move_until_s = 0.015;
  s.walls.push_back(floor);
  Particles p;
  p.add(0, 0, 0, 0, 1e-3, 1e-3, 2500);
  Engine engine(s, p);
  engine.run_steps(7000);  // t = 0.014 s: the wall has risen 0.9 mm; the sphere is on it or above
  EXPECT_GT(engine.particles().z[0], 1.9e-3 - 2e-5);
  EXPECT_GT(engine.particles().vz[0], 0.0);
  engine.run_steps(23000);  // t = 0.06 s: flown and landed on the stopped wall at 1 mm
  EXPECT_NEAR(engine.particles().z[0], 2e-3, 2e-5);
  EXPECT_NEAR(engine.particles().vz[0], 0.0, 1e-3);
}

}  // namespace
}  // namespace contactlab::dem
