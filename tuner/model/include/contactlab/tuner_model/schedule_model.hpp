// What each thread does under an OpenMP loop schedule, and how long the loop takes, from the
// per-iteration work alone (ContactDetector::iteration_work): exact for static schedules,
// simulated for dynamic and guided with libgomp's rules, priced by a small machine cost model.
// Once the costs are calibrated (cost_calibration.hpp) a prediction needs zero timed runs.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "contactlab/kernels/variant.hpp"

namespace contactlab::tuner {

// The loop's work, iteration by iteration (ContactDetector::iteration_work): what the cost
// model counts. Views, not owned.
struct WorkView {
  std::span<const std::uint32_t> tests;  // pair tests of each iteration
  // Home particles each iteration visits (cell loop: the cell's occupancy, 0 for an empty
  // cell; particle loop: 1). Empty span: 1 per iteration.
  std::span<const std::uint32_t> homes;
  // 1 where the iteration builds the stencil's neighbour ranges when it continues its
  // thread's previous iteration (cell loop: every occupied cell; particle loop: the first
  // particle of each cell), else 0. Empty span: 1 per iteration. The first iteration of a
  // chunk that does not continue its thread's stream builds whenever it has a home.
  std::span<const std::uint8_t> builds;

  WorkView() = default;
  // Tests alone: every iteration one home, one build (a particle loop in input order).
  WorkView(std::span<const std::uint32_t> tests_only) : tests(tests_only) {}     // NOLINT
  WorkView(const std::vector<std::uint32_t>& tests_only) : tests(tests_only) {}  // NOLINT
  WorkView(std::span<const std::uint32_t> tests_, std::span<const std::uint32_t> homes_,
           std::span<const std::uint8_t> builds_);  // throws for sizes other than tests'

  std::size_t size() const { return tests.size(); }
};

// Constants of the time model for one machine and one loop/order/stencil kind (a pair test in
// input order costs more than one in cell order, so each kind gets its own calibration).
// A thread's busy time is
//     tests         * seconds_per_test          (the pair tests of its iterations)
//   + iterations    * seconds_per_iteration     (loop step: an empty cell's check)
//   + homes         * seconds_per_home          (a home particle's setup and result row)
//   + builds        * seconds_per_build         (neighbour ranges: lookups in the cell index,
//                                                which dominate sparse scenes)
//   + static_chunks * seconds_per_static_chunk  (static,k: bounds of the next chunk)
//   + grabs         * seconds_per_grab          (dynamic/guided: atomic on the shared counter)
//   + stream_breaks * seconds_per_stream_break  (a chunk that does not continue the last one)
//   + cold_tests    * seconds_per_cold_test     (stencil data reloaded after a break)
// and the loop's time is seconds_per_region + the largest busy time (the final barrier waits
// for the slowest thread).
struct MachineCosts {
  double seconds_per_test = 2e-9;
  double seconds_per_iteration = 2e-9;
  double seconds_per_home = 1e-8;
  double seconds_per_build = 5e-8;
  // static,k needs no synchronisation: a thread computes its next chunk's bounds itself.
  double seconds_per_static_chunk = 5e-9;
  // dynamic/guided take every chunk from one shared counter (a compare-and-swap or fetch-add
  // on a cache line that moves between cores); a thread's last grab finds nothing and ends
  // its loop, so it pays one grab more than it has chunks.
  double seconds_per_grab = 2e-7;
  // The small-chunk locality penalty, in two parts. A chunk that starts anywhere but where the
  // thread's previous chunk ended restarts the hardware prefetch stream and writes output
  // lines that the neighbouring chunk's thread also writes (fixed cost per break) ...
  double seconds_per_stream_break = 1e-7;
  // ... and finds the stencil's particles out of this core's cache: each candidate of the
  // chunk's first iteration is a refill (the first iteration's tests measure the stencil's
  // data; the following iterations of the same cell reuse it).
  double seconds_per_cold_test = 1e-8;
  double seconds_per_region = 5e-6;  // fork, final barrier and join
  // The balanced schedule's weighing, per iteration and per build of a thread's slice, fitted
  // apart from the loop (calibrate_weighing: the balanced runs of a calibration at more than one
  // thread; the emulation sets them from the weighing it measured on the scene); negative: at
  // seconds_per_iteration and seconds_per_build, the loop's own (a one-thread calibration, where
  // nothing weighs). Cached beside the loop's constants, not in kMachineCostFields (not fitted
  // with them).
  double seconds_per_weighed_iteration = -1.0;
  double seconds_per_weighed_build = -1.0;

  // One "second" per pair test and nothing else: the simulated times are pair-test counts,
  // the pure work balance (what Takagi et al. count in their Fig. 6).
  static MachineCosts tests_only();
  friend bool operator==(const MachineCosts&, const MachineCosts&) = default;
};

// Every constant of MachineCosts by name, in the order calibration fits them.
inline constexpr std::array<std::pair<const char*, double MachineCosts::*>, 9> kMachineCostFields{{
    {"seconds_per_region", &MachineCosts::seconds_per_region},
    {"seconds_per_test", &MachineCosts::seconds_per_test},
    {"seconds_per_iteration", &MachineCosts::seconds_per_iteration},
    {"seconds_per_home", &MachineCosts::seconds_per_home},
    {"seconds_per_build", &MachineCosts::seconds_per_build},
    {"seconds_per_static_chunk", &MachineCosts::seconds_per_static_chunk},
    {"seconds_per_grab", &MachineCosts::seconds_per_grab},
    {"seconds_per_stream_break", &MachineCosts::seconds_per_stream_break},
    {"seconds_per_cold_test", &MachineCosts::seconds_per_cold_test},
}};

// What one thread does under a schedule.
struct ThreadShare {
  std::uint64_t tests = 0;
  std::uint64_t iterations = 0;
  std::uint64_t homes = 0;
  std::uint64_t builds = 0;         // neighbour-range builds, the breaks' included
  std::uint64_t chunks = 0;         // chunks executed (static block: 1 when it has iterations)
  std::uint64_t grabs = 0;          // dynamic/guided: chunks + the final empty grab; static: 0
  std::uint64_t stream_breaks = 0;  // chunks not starting where this thread's previous ended
  std::uint64_t cold_tests = 0;     // sum of the first iteration's tests over the breaks
  double seconds = 0.0;             // busy time under the costs
};

// One chunk as executed, in the order the schedule hands chunks out.
struct ChunkAssignment {
  std::uint64_t begin = 0;  // first iteration
  std::uint64_t end = 0;    // one past the last
  int thread = 0;
  friend bool operator==(const ChunkAssignment&, const ChunkAssignment&) = default;
};

struct ScheduleOutcome {
  std::vector<ThreadShare> threads;
  std::vector<ChunkAssignment> chunks;  // filled only when asked for (record_chunks)
  bool self_scheduled = false;          // dynamic/guided/chunk sequence: grabs are paid
  double makespan_seconds = 0.0;        // seconds_per_region + max thread seconds
  double imbalance = 0.0;               // (max - mean) / max of thread seconds
  double test_imbalance = 0.0;          // (max - mean) / max of thread tests
  std::uint64_t max_thread_tests = 0;
  std::uint64_t total_chunks = 0;
};

// A work view with its prefix sums, which make a chunk's counts O(1): simulations of many
// schedules of one loop share them (an 8-million-cell loop's sums cost more than a simulation).
// The viewed data must outlive it and stay unchanged.
class PreparedWork {
 public:
  explicit PreparedWork(WorkView work);
  const WorkView& view() const { return work_; }
  std::uint64_t iterations() const { return work_.size(); }
  std::uint64_t tests(std::uint64_t begin, std::uint64_t end) const;
  std::uint64_t homes(std::uint64_t begin, std::uint64_t end) const;
  std::uint64_t builds(std::uint64_t begin, std::uint64_t end) const;

 private:
  WorkView work_;
  std::vector<std::uint64_t> tests_;
  std::vector<std::uint64_t> homes_, builds_;  // empty where the view's are: 1 per iteration
};

// Distributes `work` (pair tests per iteration, loop order) over `threads` threads:
// - static, chunk 0 (block): libgomp gives thread t iterations [t*q + min(t, r), ...) with
//   q = M / P, r = M % P, the first r threads one more (gomp_iter_static_next, chunk_size 0);
// - static,k: chunk c = [c*k, (c+1)*k) goes to thread c % P (gomp_iter_static_next);
// - dynamic,k: chunks of k in loop order, each to the thread that becomes free first;
// - guided,k: as dynamic, chunk sizes from self_scheduling_chunk_sizes();
// - balanced: one block per thread, block t starting where the prefix of tests plus
//   kHomeTests (balanced_blocks.hpp) per home reaches t / P of the whole (the detector weighs
//   a home by its cell's stencil, without the tiles' extra candidates), each thread first
//   weighing an equal slice (its iterations and a build per cell, at the weighing's costs).
// The self-scheduled kinds are simulated on the cost model's clock; equal free times go to the
// thread that has taken fewer chunks, then the lowest id (so with tests_only() costs every
// thread still starts with one chunk, as in a real run, even when chunks have no work).
// Throws std::invalid_argument for threads < 1, chunk < 0, or chunk 0 with dynamic/guided.
ScheduleOutcome simulate_schedule(const PreparedWork& work, int threads, const Schedule& schedule,
                                  const MachineCosts& costs = MachineCosts::tests_only(),
                                  bool record_chunks = false);
ScheduleOutcome simulate_schedule(WorkView work, int threads, const Schedule& schedule,
                                  const MachineCosts& costs = MachineCosts::tests_only(),
                                  bool record_chunks = false);

// Self-scheduling with an arbitrary chunk-size sequence (factoring, trapezoid, ...): chunk j
// has chunk_sizes[j] iterations (the last is cut at the loop's end; sizes past the end are
// ignored; if the sizes run out before the end, the last size repeats). Priced as dynamic.
// Throws std::invalid_argument for threads < 1, an empty sequence or a zero size.
ScheduleOutcome simulate_chunk_sequence(WorkView work, int threads,
                                        std::span<const std::uint64_t> chunk_sizes,
                                        const MachineCosts& costs = MachineCosts::tests_only(),
                                        bool record_chunks = false);

// The chunk sizes a self-scheduled loop of `iterations` hands out, in grab order:
// dynamic,k: k, k, ..., the rest; guided,k: libgomp's gomp_iter_guided_next (libgomp/iter.c):
//   n = iterations left; q = ceil(n / P); if (q < k) q = k; if (q > n) q = n.
// Throws std::invalid_argument for static schedules, threads < 1 or chunk < 1.
std::vector<std::uint64_t> self_scheduling_chunk_sizes(std::uint64_t iterations, int threads,
                                                       const Schedule& schedule);

// Pair tests per thread: simulate_schedule with tests_only() costs.
std::vector<std::uint64_t> thread_tests(WorkView work, int threads, const Schedule& schedule);

// (max - mean) / max of per-thread loads: 0 when balanced, 1 - 1/P when one thread does all.
// 0 for an empty span or all zeros.
double imbalance(std::span<const double> per_thread);
double imbalance(std::span<const std::uint64_t> per_thread);

// 1, 2, 4, ... up to largest_chunk (included when a power of two). Throws for largest_chunk < 1.
std::vector<int> log2_chunk_grid(int largest_chunk = 65536);

// A chunked deal's outcome is only as safe as its chunks are many: with a few chunks a thread,
// which thread draws the dense ones decides the time, from process to process. Tried as a new
// user would (300,000 clustered particles, 2 threads), the search chose dynamic,65536 (under 5
// chunks a thread): 6 fresh processes ran it in 0.0184 - 0.0359 s where dynamic,1024 ran
// 0.0154 - 0.0196. So a tuner offers only chunks that leave every thread at least
// kMinChunksPerThread of the loop's iterations (then one chunk is at most 1/16 of a thread's
// share); the block schedule (chunk 0), one deal per thread, is the exception that keeps its
// rows in place. At least the grid's smallest chunk is kept.
inline constexpr int kMinChunksPerThread = 16;
std::vector<int> balanced_chunk_grid(std::span<const int> grid, std::size_t iterations,
                                     int threads);

struct CandidatePrediction {
  int chunk = 0;
  double predicted_seconds = 0.0;
  double imbalance = 0.0;  // of thread seconds
  std::uint64_t max_thread_tests = 0;
  std::uint64_t total_chunks = 0;
};

struct ChunkPrediction {
  int best_chunk = 0;
  double best_seconds = 0.0;
  std::vector<CandidatePrediction> candidates;  // in the order given
};

// Predicts the loop time of `kind` with every candidate chunk (0 = static block, static only)
// and returns the fastest; equal predictions prefer the larger chunk (better locality).
// Throws std::invalid_argument for no candidates or an invalid schedule.
ChunkPrediction predict_best_chunk(const PreparedWork& work, int threads, ScheduleKind kind,
                                   const MachineCosts& costs,
                                   std::span<const int> candidate_chunks);
ChunkPrediction predict_best_chunk(WorkView work, int threads, ScheduleKind kind,
                                   const MachineCosts& costs,
                                   std::span<const int> candidate_chunks);

}  // namespace contactlab::tuner
