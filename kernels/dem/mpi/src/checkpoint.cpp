// A decomposed run's checkpoint, assembled on rank 0 (dem_mpi/checkpoint.hpp).
#include "contactlab/dem_mpi/checkpoint.hpp"

#include <algorithm>
#include <cstring>
#include <unordered_map>
#include <vector>

#include "contactlab/dem/checkpoint.hpp"
#include "contactlab/dem_mpi/gather.hpp"
#include "contactlab/mpi/runtime.hpp"

namespace contactlab::dem::mpi {

void write_checkpoint(MPI_Comm comm, const Engine& engine, const HaloExchange& halo, int frames,
                      const std::string& path) {
  write_checkpoint(comm, engine, halo, gather_run(comm, engine, halo), frames, path);
}

void write_checkpoint(MPI_Comm comm, const Engine& engine, const HaloExchange& halo,
                      GatheredRun run, int frames, const std::string& path) {
  const Particles& p = engine.particles();
  const PairList& q = engine.pairs();
  // The springs of the pairs with an own particle (a pair across a boundary comes from both
  // ranks, with the same bits).
  std::vector<char> springs;
  for (std::size_t k = 0; k < q.size(); ++k) {
    if (halo.is_ghost(q.i[k]) && halo.is_ghost(q.j[k])) continue;
    if (q.hx[k] == 0.0 && q.hy[k] == 0.0 && q.hz[k] == 0.0) continue;
    const std::uint32_t a = p.id[q.i[k]], b = p.id[q.j[k]];
    const double sign = a < b ? 1.0 : -1.0;
    const std::uint64_t key = spring_key(a, b);
    const double s[3] = {sign * q.hx[k], sign * q.hy[k], sign * q.hz[k]};
    springs.insert(springs.end(), reinterpret_cast<const char*>(&key),
                   reinterpret_cast<const char*>(&key) + sizeof key);
    springs.insert(springs.end(), reinterpret_cast<const char*>(s),
                   reinterpret_cast<const char*>(s) + sizeof s);
  }
  constexpr std::size_t kEntry = sizeof(std::uint64_t) + 3 * sizeof(double);
  const std::vector<char> all_springs = gather_bytes(comm, springs, kEntry);
  contactlab::mpi::run_checked(comm, [&] {
    if (contactlab::mpi::rank_of(comm) != 0) return;
    Particles& gathered = run.particles;
    // The order and the list of the last rebuild: the builder on the positions it saw then.
    Particles then = gathered;
    then.x = then.x0;
    then.y = then.y0;
    then.z = then.z0;
    PairList pairs;
    NeighborBuilder builder;
    const EngineSettings& settings = engine.settings();
    builder.rebuild(then, pairs, settings.domain, settings.skin, settings.threads);
    std::unordered_map<std::uint32_t, std::uint32_t> index_of;
    for (std::size_t a = 0; a < gathered.size(); ++a) {
      index_of.emplace(gathered.id[a], static_cast<std::uint32_t>(a));
    }
    std::vector<std::uint32_t> order(gathered.size());
    for (std::size_t a = 0; a < then.size(); ++a) order[a] = index_of.at(then.id[a]);
    gathered.permute(order);
    std::unordered_map<std::uint64_t, std::size_t> spring_at;
    for (std::size_t at = 0; at < all_springs.size(); at += kEntry) {
      std::uint64_t key = 0;
      std::memcpy(&key, all_springs.data() + at, sizeof key);
      spring_at.emplace(key, at + sizeof key);
    }
    for (std::size_t k = 0; k < pairs.size(); ++k) {
      const std::uint32_t a = gathered.id[pairs.i[k]], b = gathered.id[pairs.j[k]];
      const auto found = spring_at.find(spring_key(a, b));
      if (found == spring_at.end()) continue;
      double s[3];
      std::memcpy(s, all_springs.data() + found->second, sizeof s);
      const double sign = a < b ? 1.0 : -1.0;
      pairs.hx[k] = sign * s[0];
      pairs.hy[k] = sign * s[1];
      pairs.hz[k] = sign * s[2];
    }
    dem::write_checkpoint(run.state, gathered, pairs, frames, path);
  });
}

}  // namespace contactlab::dem::mpi
