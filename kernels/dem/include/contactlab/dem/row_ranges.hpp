#pragma once
// The ordered force pass's row ranges, one contiguous range of particles per thread, placed so
// that the threads finish together: split by work (a row's pairs and its particle), then moved
// step by step by each thread's measured speed.
//
// Why: after its pairs a thread waits for the next threads' rows (RowsDone, below), and the
// pass ends with a barrier, so the slowest thread sets the step. On the 2-core VM one thread's busy
// time per step ran 10 - 15 % above the other's for seconds at a time, in either thread, on the
// same rows (the host's load, not the work), and the other waited: a static split cannot follow
// that, and on a scene whose particles do not all have the same pairs (a hopper's packed fill above
// its falling stream) a split by particle count is uneven at any thread count. Where a range starts
// changes no bit of the result (force_pass.hpp), so the ranges may follow the clock.
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace contactlab::dem {

class RowRanges {
 public:
  // Range starts are multiples of this (the passes' eight-lane loads start on a cache line).
  static constexpr std::size_t kAlign = 8;
  // Weight of each new measurement in a thread's running speed: about the last five steps.
  static constexpr double kSmoothing = 0.2;

  // The bounds for `threads` threads (threads + 1 values, from 0 to n) over n particles and
  // their list's rows (its CSR offsets, n + 1 values; any other size, e.g. before the first
  // list, counts the particles only): from the speeds measured so far, or equal work where
  // there are none (a new thread count, the first step).
  std::span<const std::size_t> plan(std::span<const std::uint32_t> rows, std::size_t n,
                                    std::size_t threads);
  // Thread t's busy seconds in the pass just run on the bounds of the last plan (each thread
  // its own slot: no lock).
  void record(std::size_t t, double busy_s);
  // The measured speeds folded in (after the pass, on one thread).
  void learn(std::span<const std::uint32_t> rows);
  // Seconds per unit of work (a pair or a particle) of each thread, as learned (0: not yet).
  std::span<const double> seconds_per_unit() const { return rate_; }
  std::span<const std::size_t> bounds() const { return bounds_; }

 private:
  std::vector<std::size_t> bounds_;
  std::vector<double> rate_, busy_, speed_;
};

// The ordered pass's signals between threads, instead of a barrier of the whole team after the
// pairs: thread t announces that its rows of pass `pass` are done, and waits only for the later
// threads whose rows reach its particles (their j sides for it are complete, and they have read
// its kinematics blocks, which its drift rewrites). At two threads the last thread no longer
// waits for the first before finishing its own particles; at P threads a thread waits for its
// neighbours, not for the slowest of all.
class RowsDone {
 public:
  // One signal per thread (kept from step to step: a pass's number tells old from new).
  void resize(std::size_t threads);
  // Thread t's rows of pass `pass` are done (a release: its j sides and reads come before).
  void announce(std::size_t t, std::uint64_t pass);
  // Until thread u has announced pass `pass` or a later one (an acquire; pass numbers rise),
  // pausing, then yielding the core (an oversubscribed team: the thread awaited may need this
  // one's core to run).
  void wait_for(std::size_t u, std::uint64_t pass);

 private:
  static constexpr std::size_t kStride = 8;  // 64 bytes apart: a cache line each
  std::vector<std::uint64_t> signals_;
};

// The work of particles [0, a): their pairs (none without rows) plus one per particle (on the
// settled bed a pair through the pass and a particle through the finish and drift cost about
// the same, 10 ns).
inline std::uint64_t work_before(std::span<const std::uint32_t> rows, std::size_t a) {
  return (rows.empty() ? 0 : std::uint64_t{rows[a]}) + a;
}

}  // namespace contactlab::dem
