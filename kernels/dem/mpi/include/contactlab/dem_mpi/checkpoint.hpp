// Checkpoints of a decomposed run: rank 0 gathers every rank's own particles and the springs of
// every pair with an own particle, and writes the file one process would have written at that
// step (dem/checkpoint.hpp's format): the particles in the order and the list in the rows of
// the last rebuild, rebuilt on rank 0 from the positions then (x0) with the same builder.
// One process restores it and continues bit-identically to the one-process run.
#pragma once

#include <mpi.h>

#include <string>

#include "contactlab/dem/engine.hpp"
#include "contactlab/dem_mpi/gather.hpp"
#include "contactlab/dem_mpi/halo_exchange.hpp"

namespace contactlab::dem::mpi {

// Collective. The counters are summed over the ranks (the sink's, the large overlaps: a pair
// across a boundary counted on both sides), the initial energy too (each rank's share).
void write_checkpoint(MPI_Comm comm, const Engine& engine, const HaloExchange& halo, int frames,
                      const std::string& path);
// The same from the run gathered at this step (gather_run), when its outputs need it too.
void write_checkpoint(MPI_Comm comm, const Engine& engine, const HaloExchange& halo,
                      GatheredRun run, int frames, const std::string& path);

}  // namespace contactlab::dem::mpi
