// The spatial decomposition of a DEM run over processes: slabs along one axis, each process
// owning the particles whose centre lies in its slab and holding, as ghosts, those within the
// halo width (the neighbour list's reach) of it. The cuts balance the work of the step, each
// particle weighing one plus half its neighbour-list pairs (the force pass's cost per listed
// pair and the per-particle passes' cost per particle are about equal: docs/dem.md), as the
// detection's partition balances candidate pairs. No MPI here: `dem partition` and the MPI run
// compute the same slabs from the same particles.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "contactlab/dem/engine.hpp"
#include "contactlab/dem/pair_list.hpp"
#include "contactlab/dem/particles.hpp"

namespace contactlab::dem {

struct Slabs {
  int axis = 2;
  // Along a periodic axis the slabs tile [lo, hi) and the halo wraps; otherwise the first and
  // last slab reach to -inf and +inf (walls bound the particles, and a particle leaving
  // through the sink's side stays owned until the sink takes it).
  bool periodic = false;
  double lo = 0.0, hi = 0.0;
  // ranks + 1 boundaries: rank r owns lo_r <= c < hi_r with lo_r = cuts[r], hi_r = cuts[r + 1].
  std::vector<double> cuts;

  int ranks() const { return static_cast<int>(cuts.size()) - 1; }
  // The coordinate wrapped into [lo, hi) on a periodic axis (the neighbour list's own wrap).
  double wrap(double c) const;
  // The rank owning a particle at coordinate c (wrapped first).
  int owner(double c) const;
  // Appends the ranks other than `self` whose slab, widened by `halo` on both sides (across the
  // periodic boundary too), holds c: where a particle there is a ghost. Each rank once.
  void ranks_within(double c, double halo, int self, std::vector<int>& out) const;
};

// The particles rank `rank` owns under `slabs`, every array kept, in their order.
Particles slab_particles(const Slabs& slabs, const Particles& particles, int rank);

// The work of each particle as the slabs weigh it: 1 + half its pairs in `pairs` (the
// neighbour list of the particles in their current order).
std::vector<double> particle_work(const Particles& particles, const PairList& pairs);

// Slabs along `axis` of the domain, cut where the running work (particles ordered by their
// coordinate) crosses r W / ranks, halfway between the two particles there. Every rank's work
// is then W / ranks within one particle's; ranks beyond the particles get empty slabs.
// Throws InputError for ranks < 1 or an axis outside 0-2.
Slabs balance_slabs(const Particles& particles, std::span<const double> work, int ranks, int axis,
                    const Domain& domain);

// The axis along which the particles spread the most (the periodic extent where periodic).
int longest_axis(const Particles& particles, const Domain& domain);
// "x", "y", "z"; parse_axis throws InputError for anything else.
std::string axis_name(int axis);
int parse_axis(const std::string& text);

// Each rank's particles, work and ghosts (particles within `halo` of its slab owned by another
// rank) under `slabs`, and the largest work over the mean: what `dem partition` reports.
struct SlabLoad {
  std::vector<std::uint64_t> particles, ghosts;
  std::vector<double> work;
  double imbalance = 1.0;  // largest work / mean work
};
SlabLoad slab_load(const Slabs& slabs, const Particles& particles, std::span<const double> work,
                   double halo);

// A run's decomposition from its start: the neighbour list of all its particles (one process)
// weighs them, the slabs balance that work along `axis` (-1: the longest), and the halo is the
// list's reach, 2 r_max + skin, with the skin the engine will use (the settings' or 0.1 x the
// largest diameter). Every process of a decomposed run computes the same plan.
struct SlabPlan {
  Slabs slabs;
  double skin = 0.0, halo = 0.0;  // m
  std::uint64_t pairs = 0;        // in the list that weighed the particles
  SlabLoad load;
};
SlabPlan plan_slabs(const Particles& particles, const EngineSettings& settings, int ranks,
                    int axis = -1);
// The same from a list already built over the particles (a checkpoint's).
SlabPlan plan_slabs(const Particles& particles, const PairList& pairs,
                    const EngineSettings& settings, int ranks, int axis = -1);

}  // namespace contactlab::dem
