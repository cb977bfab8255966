// What the engine asks of a spatial decomposition over processes (contactlab/dem_mpi's
// HaloExchange is the one over MPI). Each process's engine holds the particles it owns and, as
// ghosts, copies of the other processes' particles within the neighbour list's reach of its
// region; it computes every pair among them and advances them all, and the halo keeps every
// ghost equal to its owner's state after each force evaluation. A ghost then enters the next
// drift and forces with its owner's exact inputs, so an owned particle sees what it would see in
// one process; with the neighbour list's order following the ids (pair_list.hpp), its sums run
// in the one-process order and its state is the one-process state to the last bit.
#pragma once

#include <cstddef>

#include "contactlab/dem/pair_list.hpp"
#include "contactlab/dem/particles.hpp"

namespace contactlab::dem {

class Halo : public RankAgreement {
 public:
  // Summed over every process (collective, as the RankAgreement calls).
  virtual double sum_over_ranks(double local) = 0;
  // At a rebuild, before the sink: the list's springs into `carried` (by stable ids), then the
  // ghosts dropped from `particles` and the list emptied (its indices no longer hold).
  virtual void drop_ghosts(Particles& particles, PairList& pairs, CarriedSprings& carried) = 0;
  // After the sink: the particles that left this process's region go to their new owner with
  // their whole state and the springs of all their contacts (replacing those the receiver
  // held), and the new ghosts are appended.
  virtual void exchange_particles(Particles& particles, CarriedSprings& carried) = 0;
  // After the list's build has put the particles in their new order: the ghosts found there.
  virtual void index_ghosts(const Particles& particles) = 0;
  // After every force evaluation (the finish's kick included): every ghost's positions,
  // velocities, forces and torques from its owner.
  virtual void refresh_ghosts(Particles& particles) = 0;
  // Whether the particle at this index (of the order since index_ghosts) is a ghost.
  virtual bool is_ghost(std::size_t index) const = 0;
  // The particles this process owns (since index_ghosts).
  virtual std::size_t owned_count() const = 0;
  // Whether this process sends or holds ghosts now: a finish may then not drift the next step
  // in the same pass (a ghost is exchanged between its owner's kick and its drift, and its own
  // kick is wrong until then).
  virtual bool exchanges_ghosts() const = 0;
};

}  // namespace contactlab::dem
