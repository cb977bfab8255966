// The sink: particles below a height leave the run at neighbour-list rebuilds (as LIGGGHTS'
// `delete` regions do), so a discharged hopper does not keep paying for the fallen powder.
// Kept apart from the force loop: it runs only inside Engine::rebuild().
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "contactlab/dem/engine.hpp"

namespace contactlab::dem {

void Engine::remove_sunk_particles() {
  // The constructor's build keeps every particle: its start checks index the initial arrays.
  if (rebuilds_ == 0 || !(settings_.sink_below_z > -std::numeric_limits<double>::infinity())) {
    return;
  }
  Particles& p = particles_;
  const std::size_t n = p.size();
  std::vector<std::uint32_t> new_index(n, kRemoved);
  std::uint32_t kept = 0;
  double mass = 0.0, energy = 0.0;
  for (std::size_t a = 0; a < n; ++a) {
    if (p.z[a] >= settings_.sink_below_z) {
      new_index[a] = kept++;
      continue;
    }
    mass += p.mass[a];
    // The energy it takes away (kinetic + gravity), so `dissipated` stays what was dissipated.
    energy += 0.5 * p.mass[a] * (p.vx[a] * p.vx[a] + p.vy[a] * p.vy[a] + p.vz[a] * p.vz[a]) +
              0.5 / p.inv_inertia[a] * (p.wx[a] * p.wx[a] + p.wy[a] * p.wy[a] + p.wz[a] * p.wz[a]) -
              p.mass[a] * (settings_.gravity[0] * p.x[a] + settings_.gravity[1] * p.y[a] +
                           settings_.gravity[2] * p.z[a]);
  }
  if (kept == n) return;
  removed_count_ += n - kept;
  removed_mass_ += mass;
  initial_energy_ -= energy;
  // Every per-particle array compacted in place (order kept: the cell order stays good).
  p.for_each_array([&](auto& v) {
    for (std::size_t a = 0; a < n; ++a) {
      if (new_index[a] != kRemoved) v[new_index[a]] = v[a];
    }
    v.resize(kept);
  });
  // The old pair list renumbered, pairs with a removed particle dropped: the rebuild carries
  // the survivors' tangential springs from it by stable ids.
  PairList& q = pairs_;
  std::size_t m = 0;
  for (std::size_t k = 0; k < q.size(); ++k) {
    const std::uint32_t i = new_index[q.i[k]], j = new_index[q.j[k]];
    if (i == kRemoved || j == kRemoved) continue;
    q.i[m] = i;
    q.j[m] = j;
    q.image[m] = q.image[k];
    q.hx[m] = q.hx[k];
    q.hy[m] = q.hy[k];
    q.hz[m] = q.hz[k];
    ++m;
  }
  q.resize(m);
  if (kept == 0) q.build_csr(0);  // no rebuild follows: the empty list must be consistent
}

void Engine::index_ids() {
  // At every rebuild: three passes over the particles, each on the engine's threads (ids are
  // distinct, so the scatter's writes never meet).
  const std::vector<std::uint32_t>& ids = particles_.id;
  const std::size_t n = ids.size();
  std::size_t capacity = index_of_id_.size();
#pragma omp parallel for schedule(static) num_threads(settings_.threads) reduction(max : capacity)
  for (std::size_t a = 0; a < n; ++a) capacity = std::max<std::size_t>(capacity, ids[a] + 1);
  index_of_id_.resize(capacity);
  std::uint32_t* const index = index_of_id_.data();
#pragma omp parallel num_threads(settings_.threads)
  {
#pragma omp for schedule(static)
    for (std::size_t id = 0; id < capacity; ++id) index[id] = kRemoved;
#pragma omp for schedule(static)
    for (std::size_t a = 0; a < n; ++a) index[ids[a]] = static_cast<std::uint32_t>(a);
  }
}

}  // namespace contactlab::dem
