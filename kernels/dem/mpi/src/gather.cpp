// A decomposed run gathered on rank 0 (dem_mpi/gather.hpp).
#include "contactlab/dem_mpi/gather.hpp"

#include <climits>

#include "contactlab/kernels/error.hpp"
#include "contactlab/mpi/runtime.hpp"
#include "particle_records.hpp"

namespace contactlab::dem::mpi {

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
      if (sizes[r] > INT_MAX || total + sizes[r] > INT_MAX) {
        throw InputError(
            "a run of more than 2 GiB of particle state cannot be gathered on one "
            "rank yet");
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

GatheredRun gather_run(MPI_Comm comm, const Engine& engine, const HaloExchange& halo) {
  const Particles& p = engine.particles();
  std::vector<char> records;
  for (std::size_t a = 0; a < p.size(); ++a) {
    if (!halo.is_ghost(a)) append_record(p, a, records);
  }
  GatheredRun run;
  run.state = engine.state();
  double sums[4] = {static_cast<double>(run.state.large_overlaps), run.state.initial_energy,
                    static_cast<double>(run.state.removed_count), run.state.removed_mass};
  MPI_Allreduce(MPI_IN_PLACE, sums, 4, MPI_DOUBLE, MPI_SUM, comm);
  run.state.large_overlaps = static_cast<std::uint64_t>(sums[0]);
  run.state.initial_energy = sums[1];
  run.state.removed_count = static_cast<std::uint64_t>(sums[2]);
  run.state.removed_mass = sums[3];
  run.energies = engine.energies();
  const std::vector<char> all = gather_bytes(comm, records);
  run.particles.wall_spring.assign(p.wall_spring.size(), {});
  const std::size_t record = record_bytes(p);
  for (std::size_t at = 0; at < all.size(); at += record)
    read_record(all.data() + at, run.particles);
  return run;
}

}  // namespace contactlab::dem::mpi
