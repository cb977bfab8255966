// A decomposed run's start, dealt out from rank 0 (dem_mpi/start.hpp).
#include "contactlab/dem_mpi/start.hpp"

#include <algorithm>
#include <climits>
#include <cstring>
#include <vector>

#include "contactlab/kernels/error.hpp"
#include "contactlab/mpi/runtime.hpp"
#include "particle_records.hpp"

namespace contactlab::dem::mpi {
namespace {

// Rank 0's bytes for each rank, each rank's part received (items of `unit` bytes, counted in
// items so that MPI's int counts reach 2^31 items, not 2 GiB).
std::vector<char> scatter_items(MPI_Comm comm, const std::vector<std::vector<char>>& parts,
                                std::size_t unit) {
  const int ranks = contactlab::mpi::size_of(comm);
  std::vector<int> counts(static_cast<std::size_t>(ranks)), offsets(counts.size());
  std::vector<char> packed;
  int fits = 1;
  if (contactlab::mpi::rank_of(comm) == 0) {
    long long total = 0;
    for (int r = 0; r < ranks; ++r) {
      const auto items = static_cast<long long>(parts[r].size() / unit);
      if (total + items > INT_MAX) fits = 0;
      counts[r] = static_cast<int>(std::min<long long>(items, INT_MAX));
      offsets[r] = static_cast<int>(std::min<long long>(total, INT_MAX));
      total += items;
    }
    if (fits != 0) {
      packed.reserve(static_cast<std::size_t>(total) * unit);
      for (const auto& part : parts) packed.insert(packed.end(), part.begin(), part.end());
    }
  }
  MPI_Bcast(&fits, 1, MPI_INT, 0, comm);
  if (fits == 0) throw InputError("more than 2^31 - 1 particles cannot be dealt from one rank");
  int mine = 0;
  MPI_Scatter(counts.data(), 1, MPI_INT, &mine, 1, MPI_INT, 0, comm);
  MPI_Datatype item = MPI_DATATYPE_NULL;
  MPI_Type_contiguous(static_cast<int>(unit), MPI_BYTE, &item);
  MPI_Type_commit(&item);
  std::vector<char> received(static_cast<std::size_t>(mine) * unit);
  MPI_Scatterv(packed.data(), counts.data(), offsets.data(), item, received.data(), mine, item, 0,
               comm);
  MPI_Type_free(&item);
  return received;
}

void broadcast_plan(MPI_Comm comm, SlabPlan& plan, std::uint64_t& particles,
                    std::uint64_t& wall_arrays) {
  const int ranks = contactlab::mpi::size_of(comm);
  std::vector<double> header(8 + static_cast<std::size_t>(ranks) + 1);
  if (contactlab::mpi::rank_of(comm) == 0) {
    header[0] = plan.slabs.axis;
    header[1] = plan.slabs.periodic ? 1.0 : 0.0;
    header[2] = plan.slabs.lo;
    header[3] = plan.slabs.hi;
    header[4] = plan.skin;
    header[5] = plan.halo;
    header[6] = plan.load.imbalance;
    header[7] = static_cast<double>(plan.pairs);
    std::copy(plan.slabs.cuts.begin(), plan.slabs.cuts.end(), header.begin() + 8);
  }
  MPI_Bcast(header.data(), static_cast<int>(header.size()), MPI_DOUBLE, 0, comm);
  std::uint64_t counts[2] = {particles, wall_arrays};
  MPI_Bcast(counts, 2, MPI_UINT64_T, 0, comm);
  particles = counts[0];
  wall_arrays = counts[1];
  if (contactlab::mpi::rank_of(comm) == 0) return;
  plan.slabs.axis = static_cast<int>(header[0]);
  plan.slabs.periodic = header[1] != 0.0;
  plan.slabs.lo = header[2];
  plan.slabs.hi = header[3];
  plan.skin = header[4];
  plan.halo = header[5];
  plan.load.imbalance = header[6];
  plan.pairs = static_cast<std::uint64_t>(header[7]);
  plan.slabs.cuts.assign(header.begin() + 8, header.end());
}

}  // namespace

RankStart deal_start(MPI_Comm comm, const Particles* all, const PairList* pairs,
                     const EngineSettings& settings, int axis) {
  const int ranks = contactlab::mpi::size_of(comm);
  const bool root = contactlab::mpi::rank_of(comm) == 0;
  RankStart start;
  std::uint64_t wall_arrays = 0;
  contactlab::mpi::run_checked(comm, [&] {
    if (!root) return;
    start.plan = pairs != nullptr ? plan_slabs(*all, *pairs, settings, ranks, axis)
                                  : plan_slabs(*all, settings, ranks, axis);
    start.particles = all->size();
    wall_arrays = all->wall_spring.size();
  });
  broadcast_plan(comm, start.plan, start.particles, wall_arrays);
  // Each rank's own particles, whole records.
  std::vector<std::vector<char>> records(root ? static_cast<std::size_t>(ranks) : 0);
  std::vector<std::vector<char>> springs(records.size());
  Particles shape;
  shape.wall_spring.assign(wall_arrays, {});
  if (root) {
    const Slabs& slabs = start.plan.slabs;
    const auto& c = all->coordinate(slabs.axis);
    for (std::size_t a = 0; a < all->size(); ++a)
      append_record(*all, a, records[slabs.owner(c[a])]);
    // A touching pair's spring to every rank whose slab widened by two halos holds its first
    // particle: the ranks that may list the pair at the first rebuild, with room to spare.
    std::vector<int> near;
    for (std::size_t k = 0; pairs != nullptr && k < pairs->size(); ++k) {
      const PairList& q = *pairs;
      if (q.hx[k] == 0.0 && q.hy[k] == 0.0 && q.hz[k] == 0.0) continue;
      const std::uint32_t a = all->id[q.i[k]], b = all->id[q.j[k]];
      const double sign = a < b ? 1.0 : -1.0;  // seen from i: turned to the lower id's view
      const std::uint64_t key = spring_key(a, b);
      const double s[3] = {sign * q.hx[k], sign * q.hy[k], sign * q.hz[k]};
      const double at = c[q.i[k]];
      near.assign(1, slabs.owner(at));
      slabs.ranks_within(at, 2.0 * start.plan.halo, near.front(), near);
      for (const int r : near) {
        std::vector<char>& out = springs[r];
        out.insert(out.end(), reinterpret_cast<const char*>(&key),
                   reinterpret_cast<const char*>(&key) + sizeof key);
        out.insert(out.end(), reinterpret_cast<const char*>(s),
                   reinterpret_cast<const char*>(s) + sizeof s);
      }
    }
  }
  const std::size_t record = record_bytes(shape);
  const std::vector<char> mine = scatter_items(comm, records, record);
  start.own = std::move(shape);
  for (std::size_t at = 0; at < mine.size(); at += record) read_record(mine.data() + at, start.own);
  constexpr std::size_t kEntry = sizeof(std::uint64_t) + 3 * sizeof(double);
  const std::vector<char> near_springs = scatter_items(comm, springs, kEntry);
  for (std::size_t at = 0; at < near_springs.size(); at += kEntry) {
    std::uint64_t key = 0;
    double s[3];
    std::memcpy(&key, near_springs.data() + at, sizeof key);
    std::memcpy(s, near_springs.data() + at + sizeof key, sizeof s);
    start.springs.add(key, s[0], s[1], s[2]);
  }
  return start;
}

}  // namespace contactlab::dem::mpi
