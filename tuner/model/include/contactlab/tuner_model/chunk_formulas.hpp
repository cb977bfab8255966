// Classic closed-form chunk sizes from the loop-scheduling literature: the baselines the
// model-based and measured chunk choices are compared against.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "contactlab/tuner_model/schedule_model.hpp"

namespace contactlab::tuner {

// Mean and spread of one iteration's time, from the work and the calibrated costs:
// time_i = seconds_per_iteration + homes_i * seconds_per_home + builds_i * seconds_per_build
//          + tests_i * seconds_per_test.
struct IterationTimeStatistics {
  std::uint64_t iterations = 0;
  double mean_tests = 0.0;
  double stddev_tests = 0.0;  // population standard deviation
  double mean_seconds = 0.0;
  double stddev_seconds = 0.0;
};
IterationTimeStatistics iteration_time_statistics(WorkView work, const MachineCosts& costs);

// Kruskal & Weiss (1985), fixed-size chunking for self-scheduling:
//   k = (sqrt(2) * N * h / (sigma * P * sqrt(ln P)))^(2/3)
// N iterations, P threads, h = overhead of taking one chunk (seconds), sigma = standard
// deviation of one iteration's time (seconds). Rounded to nearest and clamped to
// [1, ceil(N / P)] (a larger chunk cannot balance anything); ceil(N / P) when P = 1 or
// sigma = 0 (nothing to balance). Throws std::invalid_argument for P < 1, h < 0, sigma < 0.
int kruskal_weiss_chunk(std::uint64_t iterations, int threads, double overhead_seconds,
                        double sigma_seconds);
// The same with h = costs.seconds_per_grab and sigma from iteration_time_statistics().
int kruskal_weiss_chunk(WorkView work, int threads, const MachineCosts& costs);

// Factoring (Hummel, Schonberg & Flynn 1992): chunks are handed out in batches of P equal
// chunks; with R iterations left at the batch start, each chunk is ceil(R / (x * P)).
// The practical variant fixes x = 2 (each batch takes about half of what is left).
// factoring_chunk_sequence gives every chunk in grab order (the last ones cut at the loop's
// end) for simulate_chunk_sequence(); factoring_chunk gives the first batch's chunk,
// ceil(N / (x P)), as a fixed k. Throws std::invalid_argument for P < 1 or x < 1.
std::vector<std::uint64_t> factoring_chunk_sequence(std::uint64_t iterations, int threads,
                                                    double x = 2.0);
int factoring_chunk(std::uint64_t iterations, int threads, double x = 2.0);

// The original factoring rule with x from the iteration-time statistics (mean mu, standard
// deviation sigma), recomputed per batch: b = P sigma / (2 sqrt(R) mu),
// x = 1 + b^2 + b sqrt(b^2 + 2). Throws for P < 1, mean <= 0 or sigma < 0.
std::vector<std::uint64_t> factoring_chunk_sequence(std::uint64_t iterations, int threads,
                                                    double mean_seconds, double sigma_seconds);

// Guided self-scheduling (Polychronopoulos & Kuck 1987): each grab takes ceil(R / P) of the R
// iterations left; the fixed k reported is the first grab, ceil(N / P). The full sequence is
// self_scheduling_chunk_sizes(N, P, {kGuided, 1}). Throws for P < 1.
int guided_self_scheduling_chunk(std::uint64_t iterations, int threads);

// The trivial choices: ceil(N / P) (static,k with it is the block partition: one chunk per
// thread) and ceil(N / (8 P)) (eight chunks per thread). At least 1. Throw for P < 1.
int block_chunk(std::uint64_t iterations, int threads);
int eighth_block_chunk(std::uint64_t iterations, int threads);

struct NamedChunk {
  std::string name;  // "kruskal_weiss", "factoring", "guided_self_scheduling", "block",
                     // "eighth_block"
  int chunk = 0;
  std::string inputs;  // the inputs used, for reports: "N=...,P=...,h=...,sigma=..."
};

// Every formula above for this loop, in that order.
std::vector<NamedChunk> classic_chunks(WorkView work, int threads, const MachineCosts& costs);

}  // namespace contactlab::tuner
