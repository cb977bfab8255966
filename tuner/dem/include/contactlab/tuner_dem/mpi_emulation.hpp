// `emulate dem-mpi`: the step of a decomposed DEM run (dem run --mpi) at rank counts this
// machine lacks, from the slabs' per-rank work and ghosts and a stated communication model.
// Predicted, not measured: every output says so.
//
// Per rank r and step: compute_r = c (W_r + g_r w), with W_r its own particles' work (1 + half
// their pairs), g_r its ghosts (each integrated and paired again, at the mean work w), and c
// the seconds per unit of work measured in one process; exchange_r = 2 n_r L + B_r / beta, with
// n_r its neighbouring ranks (a message each way per step), B_r the bytes it sends and receives
// (15 doubles a ghost) and L, beta the stated latency and bandwidth; the step is the slowest
// rank's compute + exchange, plus the rebuild decision's reduction, 2 L ceil(log2 R). Weak
// scaling stacks copies of the scene along the slab axis, one per rank: every rank then has the
// one-process work, two neighbours and the ghosts within the halo of the scene's two ends.
#pragma once

#include <cstdint>
#include <vector>

#include "contactlab/dem/slabs.hpp"

namespace contactlab::dem {

struct NetworkModel {
  double latency_s = 1.5e-6;  // per message
  double bandwidth = 5e9;     // bytes/s
};

struct DemMpiPoint {
  int ranks = 1;
  double step_s = 0.0;      // predicted
  double compute_s = 0.0;   // of the slowest rank
  double exchange_s = 0.0;  // of the slowest rank
  double reduction_s = 0.0;
  double speedup = 1.0;    // strong: step(1) / step(R); weak: step(1) / step(R) at R x N
  double imbalance = 1.0;  // largest work / mean
  std::uint64_t ghosts_max = 0;
  int neighbours_max = 0;
};

// Bytes a ghost costs per step (x, v, w, f, t).
inline constexpr double kGhostBytes = 15 * 8;

// Strong scaling: the particles and their list (`pairs`) over each rank count.
std::vector<DemMpiPoint> emulate_dem_mpi_strong(const Particles& particles, const PairList& pairs,
                                                const EngineSettings& settings,
                                                const std::vector<int>& ranks, int axis,
                                                double seconds_per_work,
                                                const NetworkModel& network);
// Weak scaling: R stacked copies of the scene along the slab axis, one per rank.
std::vector<DemMpiPoint> emulate_dem_mpi_weak(const Particles& particles, const PairList& pairs,
                                              const EngineSettings& settings,
                                              const std::vector<int>& ranks, int axis,
                                              double seconds_per_work, const NetworkModel& network);

}  // namespace contactlab::dem
