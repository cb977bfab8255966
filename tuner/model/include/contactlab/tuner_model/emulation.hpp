// Emulating machines larger than this one, from what this one can measure: more threads than it
// has cores (a trace replayed under each schedule) and more MPI processes than it can run (each
// rank's exact work plus a stated communication model). Pure functions: the callers time the
// kernels (thread_emulation.hpp) and label every value these return "emulated" or "predicted".
//
// The trace of a detection loop is its exact work per iteration (ContactDetector::
// iteration_work) priced by the calibrated machine costs (schedule_model.hpp), scaled so that
// its one-thread replay equals the loop's measured one-thread time: the scene's own memory
// behaviour at one thread is in the anchor, the schedule's balance and overheads in the replay.
// What no replay holds: memory bandwidth and shared caches filling as threads are added (so an
// emulated speed-up beyond the cores is what the schedule allows, an upper bound on a machine
// whose memory keeps up) and caches that become large enough when the work is split (the
// paper's superlinear 16.17x at 16 threads).
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "contactlab/kernels/variant.hpp"
#include "contactlab/tuner_model/schedule_model.hpp"

namespace contactlab::tuner {

// A phase made of a serial part and a part that divides over threads: t(P) = serial + parallel/P.
struct AmdahlPhase {
  double serial_s = 0.0;
  double parallel_s = 0.0;
  double at(int threads) const;  // throws std::invalid_argument for threads < 1
  // From the phase's times at 1 and at P > 1 threads (the two points determine both parts;
  // each part is clamped at 0, so a time that does not fall is all serial and one that falls
  // faster than 1/P all parallel). Throws std::invalid_argument for p <= 1 or a time <= 0.
  static AmdahlPhase fit(double one_thread_s, int p, double p_threads_s);
  // Only a one-thread time known: all of it serial (the conservative choice).
  static AmdahlPhase serial(double one_thread_s) { return {one_thread_s, 0.0}; }
};

// A phase whose work divides over threads and whose entries, but each thread's own share, are
// passed on to the thread that owns them: t(P) = work / P + exchange (P - 1) / P^2, where
// (P - 1) / P of a thread's 1 / P of the entries belong to other threads when ownership does not
// follow the work's deal. The half stencil's assembly under chunks or a dynamic deal is one (its
// reverse entries go to the rows of the thread that owns them): from 1 and 2 threads an Amdahl
// fit called it all serial (its two-thread time no shorter than one), and the 16-core Xeon's
// static,200 assembly ran 0.73, 0.41 and 0.25 of its one-thread time at 4, 8 and 16 threads,
// where this law from its own 1 and 2 threads gives 0.67, 0.37 and 0.19.
struct ExchangePhase {
  double work_s = 0.0;           // at one thread, where nothing is passed on
  double exchange_s = 0.0;       // what passing every entry on would add
  double at(int threads) const;  // throws std::invalid_argument for threads < 1
  // From the phase's times at 1 and at P > 1 threads; the exchange is clamped at 0 (a time that
  // falls as 1 / P or faster passes nothing on). Throws std::invalid_argument for p <= 1 or a
  // time <= 0.
  static ExchangePhase fit(double one_thread_s, int p, double p_threads_s);
};

// A loop's trace anchored to its measured one-thread time.
class AnchoredLoop {
 public:
  // Throws std::invalid_argument for one_thread_s <= 0 or an invalid schedule.
  AnchoredLoop(const PreparedWork& work, const MachineCosts& costs, const Schedule& schedule,
               double one_thread_s);
  // measured one-thread time / the replay's one-thread time: how far the calibration scenes'
  // costs are from this scene's at one thread.
  double scale() const { return scale_; }
  // The loop's emulated time at `threads` under `schedule` (another chunk or kind of the same
  // loop may be asked for: the anchor is the loop's, not the schedule's).
  ScheduleOutcome replay(int threads, const Schedule& schedule) const;
  double seconds(int threads, const Schedule& schedule) const;

 private:
  const PreparedWork& work_;
  MachineCosts costs_;
  double scale_ = 1.0;
};

// (emulated - measured) / measured.
double relative_error(double emulated, double measured);

// ---- MPI processes ---------------------------------------------------------------------------

// Messages on the interconnect: a message of b bytes takes latency + b / bandwidth (Hockney's
// model); a collective over R ranks takes ceil(log2 R) such rounds (a binomial tree).
struct CommunicationModel {
  double latency_s = 1.5e-6;
  double bandwidth_bytes_per_s = 5.0e9;
  std::string source;
  double message_s(double bytes) const;
  double collective_s(int ranks, double bytes) const;  // 0 for one rank
};

// The iterations one rank of the paper's replicated detection runs: blocks of `block`
// consecutive iterations dealt round-robin over `ranks` (HomeBlocks), in loop order. The first
// iteration of each block builds its neighbour ranges afresh (the rank's previous iteration is
// elsewhere in the order).
struct RankWork {
  std::vector<std::uint32_t> tests, homes;
  std::vector<std::uint8_t> builds;
  WorkView view() const { return {tests, homes, builds}; }
};
// Throws std::invalid_argument for block < 1, ranks < 1 or rank outside [0, ranks).
RankWork replicated_rank_work(WorkView work, std::uint32_t block, int ranks, int rank);

struct MpiPrediction {
  int ranks = 1;
  int threads_per_rank = 1;
  int processes() const { return ranks * threads_per_rank; }
  double compute_s = 0.0;        // the slowest rank's loop
  double communication_s = 0.0;  // what the ranks exchange during the timed part
  double detect_s() const { return compute_s + communication_s; }
  int slowest_rank = 0;
  double rank_imbalance = 0.0;  // (max - mean) / max of the ranks' loop times
  // The deal's locality factor in compute_s (1: none applied), and compute_s before it (the
  // replay, as the predict_ functions set it).
  double locality = 1.0;
  double replay_compute_s = 0.0;
};

// `prediction` with its loop (compute_s less the fixed cost every rank pays) multiplied by a
// locality factor measured for the deal (a share of every P-th block timed alone): what the
// calibrated costs, fitted on scenes the caches hold whole, leave out when a rank or thread
// jumps from block to block of a large scene.
MpiPrediction with_locality(MpiPrediction prediction, double factor, double fixed_s);

// Replicated data (the paper's 4.4): every rank holds the whole scene and runs its blocks with
// `threads_per_rank` threads under `schedule`; the timed part ends with one reduction of the
// ranks' contact counts (8 bytes). A rank's loop costs `fixed_s` (what a run with no iteration
// costs on this scene: measured, since every rank pays it however small its share) plus `scale`
// times its replay under `costs`.
MpiPrediction predict_replicated(WorkView work, const MachineCosts& costs, double scale,
                                 std::uint32_t block, int ranks, int threads_per_rank,
                                 const Schedule& schedule, const CommunicationModel& network,
                                 double fixed_s = 0.0);

// One rank of the distributed-memory decomposition (partition.hpp): its candidate-pair work and
// the halo it receives, from how many ranks.
struct DecomposedRank {
  std::uint64_t work = 0;            // candidate pairs (full stencil)
  std::uint64_t halo_particles = 0;  // ghosts received
  std::uint64_t halo_sources = 0;    // ranks they come from (one message each)
};

// The decomposed detection: each rank's loop costs `fixed_s` plus its share of the rest of the
// one-rank loop time in proportion to its candidate work (`one_rank_s` for `total_work`), run by
// `threads_per_rank` threads as the loop's own balance allows (`thread_efficiency`, 1 = perfect);
// the halo exchange sends each ghost as `bytes_per_ghost` bytes, one message per source rank, and
// an all-to-all of the counts precedes it. Throws std::invalid_argument for no ranks or total_work
// 0.
MpiPrediction predict_decomposed(std::span<const DecomposedRank> ranks, std::uint64_t total_work,
                                 double one_rank_s, int threads_per_rank, double thread_efficiency,
                                 double bytes_per_ghost, const CommunicationModel& network,
                                 double fixed_s = 0.0);

}  // namespace contactlab::tuner
