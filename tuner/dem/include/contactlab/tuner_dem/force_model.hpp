// The zero-run model of the DEM force pass: what each force variant costs at T threads,
// predicted from the pair list alone (pairs and particles per block of rows, and which
// blocks' particles each block's j sides reach) and a few machine costs calibrated once per
// scene and thread count. The schedules are replayed as libgomp runs them (the detection
// tuner's schedule model); the report's costs (per-thread arrays, serial walls, dynamic
// grabs, j sides written into another thread's lines) each have their term.
//
// Once calibrated, a prediction needs no timed run: `dem run --variant auto --retune`
// re-prices every variant at each neighbour-list rebuild and switches when the gain is worth it.
#pragma once

#include <algorithm>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "contactlab/dem/engine.hpp"
#include "contactlab/dem/force_variant.hpp"
#include "contactlab/dem/pair_list.hpp"

namespace contactlab::dem {

// The force pass's work per block of kRowsPerBlock particles (the loop the schedules share).
struct ForceLoopWork {
  std::size_t particles = 0;
  std::vector<std::uint32_t> block_particles;  // particles of each block
  std::vector<std::uint32_t> own_pairs;        // pairs of the block's rows (its i sides)
  std::vector<std::uint32_t> j_side_pairs;     // pairs whose j is in the block
  // Per block, the other blocks its rows' j sides land in, with their pair counts:
  // reach_block[reach_offsets[b] .. reach_offsets[b + 1]) and reach_pairs alike.
  std::vector<std::uint32_t> reach_offsets, reach_block, reach_pairs;
  std::uint64_t total_pairs() const;
};
ForceLoopWork force_loop_work(const PairList& pairs, std::size_t particles);

// Seconds per unit of work at the calibrated thread count (each thread's share, as it runs
// beside the others: memory bandwidth shared).
struct ForceCosts {
  int threads = 1;
  // Per pair in a thread's blocks (full list: per side computed), by Accumulation.
  double per_pair[4] = {0, 0, 0, 0};
  // Per pair whose j lies in a block another thread runs: j's data is not in this core's cache
  // (all), and its sums are written on lines another core holds (per-thread: the array's lines
  // spread; atomic: lines moving between cores), by Accumulation.
  double per_foreign_j_side[4] = {0, 0, 0, 0};
  double per_particle_update = 0.0;        // walls, gravity, kick in the separate update loop
  double per_particle_fused = 0.0;         // the same inside the pass (update=fused)
  double per_particle_serial_walls = 0.0;  // one thread's wall contacts (walls=serial)
  double per_particle_arrays = 0.0;        // per-thread: zeroing and summing the arrays
  double per_grab = 0.0;                   // dynamic/guided: one chunk from the shared counter
  int calibration_runs = 0;
  // The calibration's own noise: the ordered pass (pair forces and update per step) timed three
  // times, (largest - smallest) / median. A predicted gain below it cannot be told from noise.
  double calibration_spread = 0.0;
  std::uint64_t calibration_steps = 0;  // timed steps per calibration run
  double calibration_seconds = 0.0;
};

struct ForcePrediction {
  double seconds = 0.0;  // one force pass (pairs, reduction, walls, update)
  double pass_seconds = 0.0, reduction_seconds = 0.0, walls_seconds = 0.0, update_seconds = 0.0;
};

ForcePrediction predict_force_pass(const ForceLoopWork& work, const ForceVariant& variant,
                                   int threads, const ForceCosts& costs);

// Builds an engine at the common start for `variant` and `threads` (a config's particles or a
// checkpoint restored).
using EngineFactory = std::function<std::unique_ptr<Engine>(const ForceVariant&, int)>;

// Fits ForceCosts at `threads` threads from a few timed runs of `steps` steps each (after one
// untimed step) of the structures that isolate each term: ordered (separate, fused, serial
// walls), full list, per-thread and atomic with static; at more than one thread, per-thread,
// full list and atomic with static,1 (the foreign j sides); per-thread dynamic,1 (the grabs).
// Ten runs at T > 1, seven at T = 1, whatever the number of candidates.
ForceCosts calibrate_force_costs(const EngineFactory& make_engine, int threads,
                                 std::uint64_t steps);

struct RankedVariant {
  ForceVariant variant;
  ForcePrediction prediction;
};
// Every candidate priced, fastest first (ties: the earlier candidate).
std::vector<RankedVariant> rank_force_variants(const ForceLoopWork& work,
                                               const std::vector<ForceVariant>& candidates,
                                               int threads, const ForceCosts& costs);

// `dem run --retune`: at each neighbour-list rebuild the candidates are priced on the new list
// (no timed run) and the variant switched when the best is predicted faster than the current
// one by more than the margin: the stated `margin` (a fraction), raised to the calibration's
// own measured spread where that is larger (a gain the calibration cannot tell from its noise
// is no reason to leave the current variant). Switching has no cost, but a prediction's noise
// should not flip the variant back and forth.
class ForceRetuner {
 public:
  ForceRetuner(ForceCosts costs, std::vector<ForceVariant> candidates, double margin)
      : costs_(costs),
        candidates_(std::move(candidates)),
        margin_(std::max(margin, costs.calibration_spread)) {}
  struct Decision {
    ForceVariant variant;         // the one to run: the best, or the current one
    ForceVariant best;            // the fastest predicted
    double predicted_gain = 0.0;  // current / best predicted time - 1
    bool switched = false;
  };
  Decision decide(const Engine& engine, const ForceVariant& current) const;
  double margin() const { return margin_; }

 private:
  ForceCosts costs_;
  std::vector<ForceVariant> candidates_;
  double margin_;
};

}  // namespace contactlab::dem
