// A decomposed run as one process would see it, assembled on rank 0: what its outputs (frames,
// pictures, the discharge CSV) and its checkpoints are written from.
#pragma once

#include <mpi.h>

#include <vector>

#include "contactlab/dem/engine.hpp"
#include "contactlab/dem_mpi/halo_exchange.hpp"

namespace contactlab::dem::mpi {

// Every rank's items of `unit` bytes each, concatenated in rank order on rank 0 (empty
// elsewhere). Collective; every rank throws InputError past 2^31 - 1 items in all.
std::vector<char> gather_bytes(MPI_Comm comm, const std::vector<char>& mine, std::size_t unit);

struct GatheredRun {
  Particles particles;  // every rank's own particles, in rank order (rank 0; empty elsewhere)
  // The time and step, and the counters summed over the ranks (the sink's; the large overlaps,
  // a pair across a boundary counted on both sides; the initial energy, each rank's share).
  Engine::State state;
  Energies energies;
  Snapshot snapshot(const EngineSettings& settings) const {
    return {particles,           settings,          state.time_s, state.step, energies,
            state.removed_count, state.removed_mass};
  }
};

// Collective.
GatheredRun gather_run(MPI_Comm comm, const Engine& engine, const HaloExchange& halo);

}  // namespace contactlab::dem::mpi
