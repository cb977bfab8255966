// Helpers of the DEM tests: a small periodic bed on a floor, bitwise comparison of states.
#pragma once

#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "contactlab/dem/engine.hpp"
#include "contactlab/kernels/rng.hpp"

namespace contactlab::dem::test {

// n polydisperse spheres (radii 0.5 to 1 mm, size ratio 1:2) in a periodic 10 x 10 mm column
// above a floor, with random velocities and spins: contacts, walls, periodic pairs, rebuilds.
inline std::pair<EngineSettings, Particles> small_bed(std::uint32_t n = 150,
                                                      double friction = 0.5) {
  EngineSettings s;
  s.law.restitution = 0.6;
  s.law.contact_time_s = 1e-4;
  s.law.friction = friction;
  s.gravity = {0, 0, -9.81};
  s.dt_s = 2e-6;
  s.domain.lo = {0, 0, 0};
  s.domain.hi = {0.01, 0.01, 0.05};
  s.domain.periodic = {true, true, false};
  s.warn_large_overlaps = false;
  Wall floor;
  floor.name = "floor";
  s.walls.push_back(floor);
  Particles p;
  Xoshiro256 rng(3);
  const double pitch = 2.2e-3;
  for (std::uint32_t k = 0; k < n; ++k) {
    const double x = (k % 4 + 0.5) * 2.5e-3, y = (k / 4 % 4 + 0.5) * 2.5e-3;
    // NOLINTNEXTLINE(bugprone-integer-division): the lattice layer, an integer on purpose
    const double z = 1.2e-3 + (k / 16) * pitch;
    p.add(k, 0, x, y, z, 5e-4 + 5e-4 * rng.uniform(), 2500.0);
    p.vx[k] = 0.3 * (2 * rng.uniform() - 1);
    p.vy[k] = 0.3 * (2 * rng.uniform() - 1);
    p.vz[k] = -0.3 * rng.uniform();
    p.wz[k] = 50 * (2 * rng.uniform() - 1);
  }
  return {s, p};
}

// The small bed over a plate with a 6 mm orifice instead of a floor, thrown down at 1 m/s: a
// quarter of the columns drain through the hole, past the sink 1 mm below the plate.
inline std::pair<EngineSettings, Particles> draining_bed() {
  auto [settings, particles] = small_bed();
  settings.walls.clear();
  Wall plate;
  plate.kind = WallKind::kOrificePlate;
  plate.name = "plate";
  plate.point = {0.005, 0.005, 0.0};
  plate.radius = 0.003;
  settings.walls.push_back(plate);
  settings.sink_below_z = -0.001;
  for (double& vz : particles.vz) vz -= 1.0;
  return {settings, particles};
}

// Every particle's state in stable-id order.
inline std::vector<double> state_by_id(const Engine& engine) {
  const Particles& p = engine.particles();
  std::vector<double> out(p.size() * 9);
  for (std::size_t a = 0; a < p.size(); ++a) {
    const double v[9] = {p.x[a],  p.y[a],  p.z[a],  p.vx[a], p.vy[a],
                         p.vz[a], p.wx[a], p.wy[a], p.wz[a]};
    std::memcpy(&out[std::size_t{9} * p.id[a]], v, sizeof v);
  }
  return out;
}

// Any two arrays of doubles (a std::vector, a particle array), bit for bit.
template <class A, class B>
bool bitwise_equal(const A& a, const B& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0;
}

}  // namespace contactlab::dem::test
