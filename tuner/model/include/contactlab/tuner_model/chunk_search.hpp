// Noise-aware measured search for the chunk size on a log2 grid, seeded by the model, and the
// exhaustive sweep that serves as its ground truth.
//
// The caller runs the kernel: measure(k) returns one or more timed samples (seconds) of the
// loop with chunk k. Calls on the same k add samples. Every comparison uses the median, and
// the final choice uses a distribution-free 95% interval of the median (statistics.hpp):
// among the chunks whose interval overlaps the fastest one's and whose median is within the
// equivalence margin of it, the LARGEST chunk wins (same speed within the noise, fewer chunk
// boundaries, better locality). The margin matters on noisy machines: with few samples every
// interval overlaps, and the overlap test alone would pick the largest chunk measured.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <span>
#include <vector>

#include "contactlab/support/statistics.hpp"
#include "contactlab/tuner_model/schedule_model.hpp"

namespace contactlab::tuner {

// Returns the timed samples (seconds, >= 0) of one run of the loop with the given chunk.
using MeasureChunk = std::function<std::vector<double>(int chunk)>;

struct SearchBudget {
  int max_evaluations = 32;                                              // calls of measure()
  double max_measure_seconds = std::numeric_limits<double>::infinity();  // wall time in measure()
};

struct ChunkSearchOptions {
  std::vector<int> grid = log2_chunk_grid();  // ascending, distinct, >= 1
  int seed_chunk = 0;  // the model's prediction (nearest grid point in log2); 0 = grid middle
  SearchBudget budget;
  double level = 0.95;
  // A larger chunk replaces the fastest only if its median is at most this much slower
  // (relative) as well as its interval overlapping the fastest one's.
  double equivalence_margin = 0.02;
  // Exhaustive sweep only: rounds over the whole grid, each in a new random order (seeded),
  // so that the machine's drift spreads over all chunks instead of favouring some.
  int rounds = 1;
  std::uint64_t order_seed = 1;
  // Exhaustive sweep only: also measure chunk 0, the schedule's one contiguous block per thread
  // (static without a chunk size), as the largest chunk there is. It is not on the grid, and on
  // the full stencil it is the only static schedule where thread 0 writes its rows in place.
  bool with_block = false;
  // After the search, re-measure every chunk whose interval overlaps the fastest one's this
  // many times (more samples, narrower intervals), then re-decide.
  int confirmation_rounds = 0;
};

struct ChunkMeasurement {
  int chunk = 0;
  std::vector<double> samples_seconds;  // all samples, in measuring order
  double median_seconds = 0.0;
  MedianInterval interval;  // of the median
  int evaluations = 0;      // calls of measure() for this chunk
};

enum class SearchStop { kConverged, kEvaluationBudget, kTimeBudget };

struct ChunkSearchResult {
  int chosen_chunk = 0;   // the largest chunk equivalent to the fastest (see above)
  int fastest_chunk = 0;  // the smallest median (ties: the larger chunk)
  std::vector<ChunkMeasurement> measured;  // ascending chunk, the block (chunk 0) last
  int evaluations = 0;                     // calls of measure()
  double measuring_seconds = 0.0;          // wall time spent inside measure()
  double sampled_seconds = 0.0;            // sum of all samples returned
  SearchStop stop = SearchStop::kConverged;

  // The measurement of `chunk`; throws std::invalid_argument when it was not measured.
  const ChunkMeasurement& at(int chunk) const;
};

// Bracket, then golden-section search on the grid index (= log2 k), from the seed:
//  1. measure the seed and its two grid neighbours; walk downhill with doubling steps until
//     the median rises (a bracket lo < best < hi);
//  2. golden-section inside the bracket, one new grid point per step, until lo and hi are the
//     best point's neighbours;
//  3. walk up from the fastest chunk while the next larger one's interval overlaps it, since
//     the larger one would be preferred;
//  4. confirmation rounds (options), then the choice above.
// Stops early, with a choice among what was measured, when the budget runs out (checked
// before each call of measure). Assumes the time is roughly unimodal in log2 k, as the balance
// (better with small k) against overhead and locality (better with large k) makes it.
// Throws std::invalid_argument for a bad grid, level or budget, or when measure() returns no
// samples or a sample that is not finite and >= 0.
ChunkSearchResult search_chunk(const MeasureChunk& measure, const ChunkSearchOptions& options);

// Measures every grid chunk options.rounds times, round by round, each round in a seeded random
// order (the budget is ignored), then makes the same choice. Ground truth for search_chunk and
// for the model: its fastest_chunk is the exhaustive best.
ChunkSearchResult exhaustive_chunk_sweep(const MeasureChunk& measure,
                                         const ChunkSearchOptions& options);

// (chosen - best) / best. Throws std::invalid_argument for best <= 0 or negative chosen.
double regret(double chosen_seconds, double best_seconds);
// Regret of `chosen_chunk` by the medians of an exhaustive sweep, against its fastest median.
// Throws when `chosen_chunk` was not measured.
double regret(const ChunkSearchResult& exhaustive, int chosen_chunk);

}  // namespace contactlab::tuner
