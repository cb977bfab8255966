// The sink: particles below a height leave the run at neighbour-list rebuilds (as LIGGGHTS'
// `delete` regions do), so a discharged hopper does not keep paying for the fallen powder.
// Kept apart from the force loop: it runs only inside Engine::rebuild().
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "contactlab/dem/engine.hpp"
#include "contactlab/kernels/count_then_fill.hpp"

namespace contactlab::dem {

bool Engine::remove_sunk_particles() {
  // The constructor's build keeps every particle: its start checks index the initial arrays.
  if (rebuilds_ == 0 || !(settings_.sink_below_z > -std::numeric_limits<double>::infinity())) {
    return false;
  }
  Particles& p = particles_;
  const std::size_t n = p.size();
  const int threads = settings_.threads;
  const double level = settings_.sink_below_z;
  const double* const z = p.z.data();
  // The particles that stay and those that leave, each in order, listed range by range on the
  // engine's threads (count_then_fill): no pass of length n on one thread (on a discharging
  // hopper a rebuild that removes comes every 15 steps or so).
  auto list = [&](std::vector<std::uint32_t>& out, bool stays) {
    count_then_fill(
        n, threads,
        [&](std::size_t first, std::size_t last) {
          std::size_t count = 0;
          for (std::size_t a = first; a < last; ++a) count += (z[a] >= level) == stays;
          return count;
        },
        [&](std::size_t total) { out.resize(total); },
        [&](std::size_t first, std::size_t last, std::size_t at) {
          for (std::size_t a = first; a < last; ++a) {
            if ((z[a] >= level) == stays) out[at++] = static_cast<std::uint32_t>(a);
          }
        });
  };
  std::vector<std::uint32_t> removed;
  list(removed, false);
  if (removed.empty()) return false;
  double mass = 0.0, energy = 0.0;
  for (const std::uint32_t a : removed) {  // in index order, as one loop over all would add
    mass += p.mass[a];
    // The energy it takes away (kinetic + gravity), so `dissipated` stays what was dissipated.
    energy += 0.5 * p.mass[a] * (p.vx[a] * p.vx[a] + p.vy[a] * p.vy[a] + p.vz[a] * p.vz[a]) +
              0.5 / p.inv_inertia[a] * (p.wx[a] * p.wx[a] + p.wy[a] * p.wy[a] + p.wz[a] * p.wz[a]) -
              p.mass[a] * (settings_.gravity[0] * p.x[a] + settings_.gravity[1] * p.y[a] +
                           settings_.gravity[2] * p.z[a]);
  }
  removed_count_ += removed.size();
  removed_mass_ += mass;
  initial_energy_ -= energy;
  // The touching pairs' springs by stable ids, while the list still indexes these particles
  // (with a halo, drop_ghosts took them already): the rebuild carries them from there. Pairs of
  // a removed particle find no partner in the new list.
  if (halo_ == nullptr) collect_springs(p, pairs_, carried_, threads);
  std::vector<std::uint32_t> kept;
  list(kept, true);
  p.gather(kept, threads);  // every per-particle array compacted, the order kept
  if (kept.empty()) {       // no rebuild follows: the empty list must be consistent
    pairs_.resize(0);
    pairs_.build_csr(0);
  } else {
    // No longer this list's particles; the rebuild overwrites it, whose arrays keep their size
    // (emptied, each would be zero-filled again on one thread).
    pairs_.rows.clear();
  }
  return true;
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
