// A decomposed run's checkpoint, assembled on rank 0 (dem_mpi/checkpoint.hpp).
#include "contactlab/dem_mpi/checkpoint.hpp"

#include <algorithm>
#include <cstring>
#include <unordered_map>
#include <vector>

#include "contactlab/dem/checkpoint.hpp"
#include "contactlab/kernels/error.hpp"
#include "contactlab/mpi/runtime.hpp"
#include "particle_records.hpp"

namespace contactlab::dem::mpi {

namespace {

// Every rank's bytes concatenated on rank 0 (empty elsewhere).
std::vector<char> gather_bytes(MPI_Comm comm, const std::vector<char>& mine) {
  const int ranks = contactlab::mpi::size_of(comm);
  const int rank = contactlab::mpi::rank_of(comm);
  const auto size = static_cast<long long>(mine.size());
  std::vector<long long> sizes(static_cast<std::size_t>(ranks));
  MPI_Gather(&size, 1, MPI_LONG_LONG, sizes.data(), 1, MPI_LONG_LONG, 0, comm);
  std::vector<int> counts(static_cast<std::size_t>(ranks)), offsets(counts.size());
  std::vector<char> all;
  if (rank == 0) {
    long long total = 0;
    for (int r = 0; r < ranks; ++r) {
      if (sizes[r] > INT32_MAX || total + sizes[r] > INT32_MAX) {
        throw InputError("a checkpoint of more than 2 GiB cannot be gathered on one rank yet");
      }
      counts[r] = static_cast<int>(sizes[r]);
      offsets[r] = static_cast<int>(total);
      total += sizes[r];
    }
    all.resize(static_cast<std::size_t>(total));
  }
  MPI_Gatherv(mine.data(), static_cast<int>(mine.size()), MPI_BYTE, all.data(), counts.data(),
              offsets.data(), MPI_BYTE, 0, comm);
  return all;
}

}  // namespace

void write_checkpoint(MPI_Comm comm, const Engine& engine, const HaloExchange& halo, int frames,
                      const std::string& path) {
  const Particles& p = engine.particles();
  const PairList& q = engine.pairs();
  // This rank's own particles, and the springs of the pairs with one of them (a pair across a
  // boundary comes from both ranks, with the same bits).
  std::vector<char> records;
  for (std::size_t a = 0; a < p.size(); ++a) {
    if (!halo.is_ghost(a)) append_record(p, a, records);
  }
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
  Engine::State state = engine.state();
  double sums[4] = {static_cast<double>(state.large_overlaps), state.initial_energy,
                    static_cast<double>(state.removed_count), state.removed_mass};
  MPI_Allreduce(MPI_IN_PLACE, sums, 4, MPI_DOUBLE, MPI_SUM, comm);
  const std::vector<char> all_records = gather_bytes(comm, records);
  const std::vector<char> all_springs = gather_bytes(comm, springs);
  contactlab::mpi::run_checked(comm, [&] {
    if (contactlab::mpi::rank_of(comm) != 0) return;
    state.large_overlaps = static_cast<std::uint64_t>(sums[0]);
    state.initial_energy = sums[1];
    state.removed_count = static_cast<std::uint64_t>(sums[2]);
    state.removed_mass = sums[3];
    Particles gathered;
    gathered.wall_spring.assign(p.wall_spring.size(), {});
    const std::size_t record = record_bytes(p);
    for (std::size_t at = 0; at < all_records.size(); at += record) {
      read_record(all_records.data() + at, gathered);
    }
    // The order and the list of the last rebuild: the builder on the positions it saw then.
    Particles then = gathered;
    then.x = then.x0;
    then.y = then.y0;
    then.z = then.z0;
    PairList pairs;
    NeighborBuilder builder;
    const EngineSettings& settings = engine.settings();
    builder.rebuild(then, pairs, settings.domain, settings.skin, engine.coefficients().mu_roll > 0,
                    settings.threads);
    std::unordered_map<std::uint32_t, std::uint32_t> index_of;
    for (std::size_t a = 0; a < gathered.size(); ++a) {
      index_of.emplace(gathered.id[a], static_cast<std::uint32_t>(a));
    }
    std::vector<std::uint32_t> order(gathered.size());
    for (std::size_t a = 0; a < then.size(); ++a) order[a] = index_of.at(then.id[a]);
    gathered.permute(order);
    std::unordered_map<std::uint64_t, std::size_t> spring_at;
    constexpr std::size_t kEntry = sizeof(std::uint64_t) + 3 * sizeof(double);
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
    dem::write_checkpoint(state, gathered, pairs, frames, path);
  });
}

}  // namespace contactlab::dem::mpi
