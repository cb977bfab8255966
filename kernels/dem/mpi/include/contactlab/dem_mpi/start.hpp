// The start of a decomposed run, made on rank 0 and dealt out: rank 0 alone holds every
// particle (the config's or a checkpoint's) and their neighbour list while it plans the slabs
// by work, then sends each rank its own particles and the springs near its slab, one message
// a rank. Memory O(N) on rank 0 only and O(N / R) on the others, as for the gathers of the
// outputs and checkpoints (gather.hpp); LAMMPS's read_data likewise reads on one process.
#pragma once

#include <mpi.h>

#include <cstdint>

#include "contactlab/dem/pair_list.hpp"
#include "contactlab/dem/particles.hpp"
#include "contactlab/dem/slabs.hpp"

namespace contactlab::dem::mpi {

struct RankStart {
  SlabPlan plan;                // rank 0's, on every rank (the per-rank load only on rank 0)
  std::uint64_t particles = 0;  // in the whole run
  Particles own;                // this rank's, every array, in rank 0's order
  // The springs of the touching pairs with a particle within two halos of this rank's slab:
  // every pair its first list can hold (HaloExchange::seed_springs).
  CarriedSprings springs;
};

// Collective. On rank 0, `all` holds the run's particles and `pairs` their list (a
// checkpoint's, with its springs) or null (a config's start: the list is built to weigh them);
// the others pass null. `axis` -1: the longest. A failure of the plan on rank 0 (no particles)
// is agreed: every rank throws InputError with its message.
RankStart deal_start(MPI_Comm comm, const Particles* all, const PairList* pairs,
                     const EngineSettings& settings, int axis);

}  // namespace contactlab::dem::mpi
