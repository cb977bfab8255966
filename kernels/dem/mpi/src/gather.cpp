// A decomposed run gathered on rank 0 (dem_mpi/gather.hpp).
#include "contactlab/dem_mpi/gather.hpp"

#include <fmt/format.h>

#include <climits>

#include "contactlab/kernels/error.hpp"
#include "contactlab/mpi/runtime.hpp"
#include "particle_records.hpp"

namespace contactlab::dem::mpi {

std::vector<char> gather_bytes(MPI_Comm comm, const std::vector<char>& mine, std::size_t unit) {
  const int ranks = contactlab::mpi::size_of(comm);
  const int rank = contactlab::mpi::rank_of(comm);
  // Counted in units (a particle's record, a spring), not bytes: MPI's int counts then reach
  // 2^31 particles, not 2 GiB.
  const auto units = static_cast<long long>(mine.size() / unit);
  std::vector<long long> sizes(static_cast<std::size_t>(ranks));
  MPI_Gather(&units, 1, MPI_LONG_LONG, sizes.data(), 1, MPI_LONG_LONG, 0, comm);
  std::vector<int> counts(static_cast<std::size_t>(ranks)), offsets(counts.size());
  std::vector<char> all;
  int fits = 1;
  if (rank == 0) {
    long long total = 0;
    for (int r = 0; r < ranks; ++r) {
      if (total + sizes[r] > INT_MAX) fits = 0;
      counts[r] = fits != 0 ? static_cast<int>(sizes[r]) : 0;
      offsets[r] = fits != 0 ? static_cast<int>(total) : 0;
      total += sizes[r];
    }
    if (fits != 0) all.resize(static_cast<std::size_t>(total) * unit);
  }
  // Every rank learns whether it fits before the collective that would need it.
  MPI_Bcast(&fits, 1, MPI_INT, 0, comm);
  if (fits == 0) {
    throw InputError(fmt::format("more than {} items of {} bytes cannot be gathered on one rank",
                                 INT_MAX, unit));
  }
  MPI_Datatype item = MPI_DATATYPE_NULL;
  MPI_Type_contiguous(static_cast<int>(unit), MPI_BYTE, &item);
  MPI_Type_commit(&item);
  MPI_Gatherv(mine.data(), static_cast<int>(units), item, all.data(), counts.data(), offsets.data(),
              item, 0, comm);
  MPI_Type_free(&item);
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
  const std::size_t record = record_bytes(p);
  const std::vector<char> all = gather_bytes(comm, records, record);
  run.particles.wall_spring.assign(p.wall_spring.size(), {});
  for (std::size_t at = 0; at < all.size(); at += record)
    read_record(all.data() + at, run.particles);
  return run;
}

}  // namespace contactlab::dem::mpi
