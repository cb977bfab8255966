// Particle arrays: growth and permutation.
#include "contactlab/dem/particles.hpp"

#include <numbers>

namespace contactlab::dem {
namespace {

template <class T>
void permute_one(std::vector<T>& v, std::span<const std::uint32_t> order) {
  std::vector<T> permuted(v.size());
  for (std::size_t a = 0; a < order.size(); ++a) permuted[a] = v[order[a]];
  v.swap(permuted);
}

}  // namespace

void Particles::resize(std::size_t n) {
  for_each_array([n](auto& v) { v.resize(n); });  // new entries are zero
}

void Particles::set_wall_count(std::size_t walls) {
  wall_spring.assign(3 * walls, std::vector<double>(size(), 0.0));
}

void Particles::add(std::uint32_t stable_id, std::uint16_t material_index, double px, double py,
                    double pz, double r, double density) {
  const std::size_t i = size();
  resize(i + 1);
  id[i] = stable_id;
  material[i] = material_index;
  x[i] = x0[i] = px;
  y[i] = y0[i] = py;
  z[i] = z0[i] = pz;
  radius[i] = r;
  mass[i] = density * 4.0 / 3.0 * std::numbers::pi * r * r * r;
  inv_mass[i] = 1.0 / mass[i];
  inv_inertia[i] = 1.0 / (0.4 * mass[i] * r * r);
}

void Particles::permute(std::span<const std::uint32_t> order) {
  for_each_array([order](auto& v) { permute_one(v, order); });
}

}  // namespace contactlab::dem
