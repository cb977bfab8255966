// DEM particles as structure of arrays (SI units), with a stable id kept through reorders.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "contactlab/kernels/aligned_vector.hpp"

namespace contactlab::dem {

// The real arrays start on a cache line (AlignedVector): the particle passes load and store them
// eight lanes at a time.
struct Particles {
  std::vector<std::uint32_t> id;  // stable id: the input order, used for output and history
  std::vector<std::uint16_t> material;
  AlignedVector<double> x, y, z;          // m
  AlignedVector<double> vx, vy, vz;       // m/s (between the two half kicks: v(t + dt/2))
  AlignedVector<double> wx, wy, wz;       // angular velocity, rad/s
  AlignedVector<double> fx, fy, fz;       // total force of the last evaluation, N
  AlignedVector<double> tx, ty, tz;       // total torque, N m
  AlignedVector<double> radius;           // m
  AlignedVector<double> mass;             // kg
  AlignedVector<double> inv_mass;         // 1/kg
  AlignedVector<double> inv_inertia;      // 1/(kg m^2), solid sphere I = 2/5 m r^2
  AlignedVector<double> x0, y0, z0;       // positions at the last neighbour-list build
  std::vector<std::uint16_t> contacts;    // contacts with force > 0 at the last evaluation
  AlignedVector<double> force_magnitude;  // |contact force| at the last evaluation, N
  // Tangential springs of the wall contacts [m]: wall w's x, y, z components are arrays
  // 3 w, 3 w + 1, 3 w + 2 (zero while the particle does not touch the wall).
  std::vector<std::vector<double>> wall_spring;

  std::size_t size() const { return x.size(); }
  // The positions along axis 0, 1 or 2.
  const AlignedVector<double>& coordinate(int axis) const {
    return axis == 0 ? x : axis == 1 ? y : z;
  }
  void resize(std::size_t n);
  void set_wall_count(std::size_t walls);
  // Adds a sphere at rest; mass from the density [kg/m^3].
  void add(std::uint32_t stable_id, std::uint16_t material_index, double px, double py, double pz,
           double r, double density);
  // Every array permuted: new index a holds what index order[a] held (gathered on `threads`
  // threads; order.size() == size()).
  void permute(std::span<const std::uint32_t> order, int threads = 1);
  // The same where `order` may leave out or repeat indices: the arrays take its length (copies
  // of a column laid side by side, tile.hpp).
  void gather(std::span<const std::uint32_t> order, int threads = 1);

  // Calls f on every per-particle array, in one fixed order (the checkpoint's): growth,
  // permutation and checkpoints all go through this one list.
  template <class F>
  void for_each_array(F&& f) {
    for_each_array_of(*this, f);
  }
  template <class F>
  void for_each_array(F&& f) const {
    for_each_array_of(*this, f);
  }

 private:
  template <class Self, class F>
  static void for_each_array_of(Self& p, F& f) {
    f(p.id);
    f(p.material);
    f(p.contacts);
    for (auto* v : {&p.x,
                    &p.y,
                    &p.z,
                    &p.vx,
                    &p.vy,
                    &p.vz,
                    &p.wx,
                    &p.wy,
                    &p.wz,
                    &p.fx,
                    &p.fy,
                    &p.fz,
                    &p.tx,
                    &p.ty,
                    &p.tz,
                    &p.radius,
                    &p.mass,
                    &p.inv_mass,
                    &p.inv_inertia,
                    &p.x0,
                    &p.y0,
                    &p.z0,
                    &p.force_magnitude}) {
      f(*v);
    }
    for (auto& v : p.wall_spring) f(v);
  }
};

}  // namespace contactlab::dem
