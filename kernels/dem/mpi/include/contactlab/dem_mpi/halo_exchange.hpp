// The DEM engine's halo over MPI (dem/halo.hpp): slabs along one axis (dem/slabs.hpp), the
// ghosts' state from their owners after every force evaluation (one message per neighbouring
// rank), and at every rebuild the migration of particles that changed slab, with the springs
// of all their contacts, and the choice of the new ghosts. Forces on ghosts are computed by both
// sides and thrown away, not returned: a pair across a boundary then costs two evaluations
// instead of one message more per step and a second summation order (which would break the
// equality with one process).
#pragma once

#include <mpi.h>

#include <cstdint>
#include <unordered_map>
#include <vector>

#include "contactlab/dem/halo.hpp"
#include "contactlab/dem/slabs.hpp"

namespace contactlab::dem::mpi {

// Where one rank's time went (summed since construction) and what it moved.
struct HaloStats {
  double refresh_s = 0.0;    // the per-step ghost exchanges
  double migration_s = 0.0;  // the rebuilds' migrations and ghost choices
  double agreement_s = 0.0;  // the reductions every rank waits in (the rebuild decision, ...)
  std::uint64_t refreshes = 0, messages = 0, migrated = 0, migrated_springs = 0;
  std::uint64_t ghosts = 0;  // now
  // The work imbalance (largest rank's work / mean, before any re-balancing) at each rebuild:
  // its mean and largest over the run, and how many rebuilds re-balanced.
  double imbalance_sum = 0.0, imbalance_max = 0.0;
  std::uint64_t imbalance_samples = 0, rebalances = 0;
  double imbalance_mean() const {
    return imbalance_samples > 0 ? imbalance_sum / static_cast<double>(imbalance_samples) : 1.0;
  }
};

class HaloExchange final : public Halo {
 public:
  // `halo_width` at least the neighbour list's reach, 2 r_max + skin [m]. At a rebuild where
  // the largest rank's work exceeds the mean by more than `rebalance_margin` (a fraction;
  // infinity: never), the slabs are cut again from the particles' work as it stands then (each
  // owned particle 1 + half its pairs), and the particles migrate to them.
  HaloExchange(MPI_Comm comm, Slabs slabs, double halo_width, double rebalance_margin = 0.1);

  double max_over_ranks(double local) override;
  Box box_over_ranks(const Box& local) override;
  double sum_over_ranks(double local) override;
  void drop_ghosts(Particles& particles, PairList& pairs, CarriedSprings& carried) override;
  void exchange_particles(Particles& particles, CarriedSprings& carried) override;
  void index_ghosts(const Particles& particles) override;
  void refresh_ghosts(Particles& particles) override;
  bool is_ghost(std::size_t index) const override { return ghost_[index] != 0; }
  std::size_t owned_count() const override { return owned_; }
  bool exchanges_ghosts() const override { return exchanges_; }

  // Springs the first rebuild carries besides the list's (a run resumed from a checkpoint:
  // the engine's list is empty then).
  void seed_springs(CarriedSprings springs) { seeds_ = std::move(springs); }

  const Slabs& slabs() const { return slabs_; }
  const HaloStats& stats() const { return stats_; }
  int rank() const { return rank_; }
  int ranks() const { return ranks_; }

 private:
  MPI_Comm comm_;
  int rank_ = 0, ranks_ = 1;
  Slabs slabs_;
  double halo_width_;
  double rebalance_margin_;
  // Per owned particle (by id), its work in the list before the rebuild.
  std::unordered_map<std::uint32_t, double> work_of_id_;
  // The rebuild's imbalance, and new cuts when it is above the margin (collective).
  void rebalance(const Particles& particles);
  std::size_t owned_ = 0;
  bool exchanges_ = false;           // ghosts sent or received since the last rebuild
  std::vector<std::uint8_t> ghost_;  // by index, since index_ghosts
  // Per rank: the ids of the owned particles sent to it as ghosts, and of the ghosts it sent
  // here (in the order they come each step); then their indices in the current order.
  std::vector<std::vector<std::uint32_t>> send_ids_, recv_ids_, send_index_, recv_index_;
  std::vector<std::vector<double>> send_buffer_, recv_buffer_;
  std::vector<MPI_Request> requests_;
  HaloStats stats_;
  CarriedSprings seeds_;
};

}  // namespace contactlab::dem::mpi
