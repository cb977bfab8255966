// The DEM force pass (private to src/): blocks of rows through the pair kernel (pair_rows), their
// outputs summed per particle (ordered: in pair order for any thread count; per-thread arrays
// or atomics: the report's accumulations), and each particle finished.
// Compiled once per instruction set (dem_isa.hpp): a toggle, no include guard.

#include <omp.h>

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <span>
#include <vector>

#include "contactlab/dem/force_variant.hpp"  // kRowsPerBlock
#include "contactlab/dem/row_ranges.hpp"     // RowsDone
#include "dem_isa.hpp"
#include "lanes.hpp"
#include "pair_block.hpp"

#if defined(CONTACTLAB_DEM_FORCE_PASS_TOGGLE) == defined(CONTACTLAB_DEM_ISA_TOGGLE)
#ifdef CONTACTLAB_DEM_FORCE_PASS_TOGGLE
#undef CONTACTLAB_DEM_FORCE_PASS_TOGGLE
#else
#define CONTACTLAB_DEM_FORCE_PASS_TOGGLE
#endif

namespace contactlab::dem::detail {
CONTACTLAB_DEM_ISA_NAMESPACE(build) {

// Where the force pass's phases end (for PhaseTimes): the pairs, the reduction (ordered: the
// j sides other threads left; per-thread: the arrays' sum), the serial walls; and where the
// ordered pass's finish before its waits begins and ends (update, though it lies among the pairs).
enum class Phase { kPairs, kReduction, kWalls, kEarlyFinishBegin, kEarlyFinishEnd };

// Combines a thread's overlap counts into the shared ones (integers: exact in any order).
inline void combine_counts(std::uint64_t here, std::uint32_t bad_here, std::uint64_t& total,
                           std::uint32_t& bad) {
  if (here > 0) {
#pragma omp atomic
    total += here;
  }
  if (bad_here != UINT32_MAX) {  // atomic: a finish on another thread may be reading it
#pragma omp critical(dem_bad_index)
    {
      const std::atomic_ref<std::uint32_t> first(bad);
      first.store(std::min(first.load(std::memory_order_relaxed), bad_here),
                  std::memory_order_relaxed);
    }
  }
}

// (1, 1, 1, r, r, r, touch, 0): a pair record times it is its force, r times its n x F_t and
// touch times its touching flag. A broadcast and a blend, not eight inserts.
[[gnu::always_inline]] inline Lanes record_scale(double r, double touch) {
  const LaneMask radius_lanes = mask_of({0, 0, 0, -1, -1, -1, 0, 0});
  return select(radius_lanes, Lanes{} + r, lanes_of({1, 1, 1, 0, 0, 0, touch, 0}));
}

// Pair b's j side (its record p, rolling torques roll[.][b]) subtracted from the sums aj of
// its j particle, of radius rj: lane by lane the scalar a - f, a - r_j c, a - (-t) = a + t
// (lane 7 unused).
template <bool kRolling>
[[gnu::always_inline]] inline void subtract_j_side(double* aj, const double* p, double rj,
                                                   const double* const* roll, std::size_t b) {
  Lanes sum = load_lanes(aj) - load_lanes(p) * record_scale(rj, -1.0);
  if constexpr (kRolling) sum -= lanes_of({0, 0, 0, roll[0][b], roll[1][b], roll[2][b], 0, 0});
  store_lanes(aj, sum);
}

// The rows [first, last) of a block (its records from pair_rows): each row's outputs summed in
// pair order (i's force, torque, touching contacts: lanes 0-6 of the sum, lane 7 zero) and
// handed to store(i, sum), and each pair handed to j_side(p, roll, k, b) after its i side (p: the
// pair's record, roll: the block's rolling torques, b: the pair's lane). A record times
// (1, 1, 1, -r_i, -r_i, -r_i, 1, 0) adds lane by lane what the scalar sums add (a + b(-c) is
// a - bc, exactly), so the sums keep their bits.
template <bool kRolling, class JSide, class Store>
inline void sum_rows(const PairList& q, std::size_t first, std::size_t last, PairBlock& blk,
                     const double* kin, JSide&& j_side, Store&& store) {
  const std::size_t k0 = q.rows[first];
  const double* rec = blk.records();
  const double* roll[3] = {blk.roll(0), blk.roll(1), blk.roll(2)};
  for (std::size_t i = first; i < last; ++i) {
    const Lanes scale = record_scale(-kin[kKinStride * i + 3], 1.0);
    Lanes sum{};
    for (std::size_t k = q.rows[i]; k < q.rows[i + 1]; ++k) {
      const std::size_t b = k - k0;
      const double* p = rec + kLanes * b;
      sum += load_lanes(p) * scale;
      // + 0 keeps every lane's bits: no sum here is -0 (sums from +0 never are).
      if constexpr (kRolling) sum += lanes_of({0, 0, 0, roll[0][b], roll[1][b], roll[2][b], 0, 0});
      j_side(p, roll, k, b);
    }
    store(i, sum);
  }
}

// As sum_rows, with store(i, sum) an assignment to acc (nothing reached i before its row): one
// flat loop over the block's pairs, where a row's end is a select, not a loop exit (rows of 0
// to 8 pairs mispredict one exit a row). The running sum starts again from +0 where the row
// changes and is stored to its particle after every pair (the row's last store stands); the
// block's particles are zeroed first, for the rows without pairs.
template <bool kRolling, class JSide>
inline void assign_rows(const PairList& q, std::size_t first, std::size_t last, PairBlock& blk,
                        const double* kin, double* acc, JSide&& j_side) {
  const std::uint32_t* rows = q.rows.data();  // in locals: the stores may alias anything
  const std::uint32_t* row_of = q.i.data();
  const std::size_t k0 = rows[first], k1 = rows[last];
  for (std::size_t a = first; a < last; ++a) store_lanes(acc + kAccStride * a, Lanes{});
  const double* rec = blk.records();
  const double* roll[3] = {blk.roll(0), blk.roll(1), blk.roll(2)};
  Lanes sum{};
  std::uint32_t current = UINT32_MAX;
  for (std::size_t k = k0; k < k1; ++k) {
    const std::uint32_t i = row_of[k];
    const std::size_t b = k - k0;
    const double* p = rec + kLanes * b;
    // The sum goes on within the row and starts again from +0 at its first pair, no branch: the
    // running sum is one chain over the block's pairs, and its latency bounded the loop (a
    // masked add for the and and the add: 1.02 - 1.05x the bed's step at one thread).
    sum = add_if(sum, load_lanes(p) * record_scale(-kin[kKinStride * i + 3], 1.0), i == current);
    if constexpr (kRolling) sum += lanes_of({0, 0, 0, roll[0][b], roll[1][b], roll[2][b], 0, 0});
    store_lanes(acc + kAccStride * i, sum);
    j_side(p, roll, k, b);
    current = i;
  }
}

// The ordered pass's sums: each row summed in registers and stored to its particle (nothing
// reached it before: its j sides come from later rows), then each j side subtracted from j's
// sum when this thread owns j (j >= own_begin); otherwise it is appended, in pair order, to
// left_for(j): the sides for j's owner, which adds them once this thread's rows are done (they come
// from later rows, so pair order still holds). Particle a's sum is therefore its own row, then its
// j sides in pair order, whatever the thread count and ranges.
template <bool kRolling, class LeftFor>
inline void accumulate_ordered(const double* kin, PairList& q, std::size_t first, std::size_t last,
                               PairBlock& blk, std::size_t own_begin, double* acc,
                               LeftFor&& left_for) {
  static_assert(LeftJSides::kRecordDoubles == kLanes && kAccStride == kLanes);
  // Out of line: inlined, its state took registers from the loop around it (the one-thread
  // step, which never leaves a side, ran 2 - 3 % slower).
  auto leave = [&](std::uint32_t j, const double* p, const double* const* roll, std::size_t b)
      __attribute__((noinline)) {
    LeftJSides& left = left_for(j);
    left.reserve_one(kRolling);
    const std::size_t at = left.count++;
    store_lanes(left.records.data() + kLanes * at, load_lanes(p));
    left.j[at] = j;
    if constexpr (kRolling) {
      left.roll_x[at] = roll[0][b];
      left.roll_y[at] = roll[1][b];
      left.roll_z[at] = roll[2][b];
    }
  };
  // In a local: the sums' stores may alias the list, whose array it would reload every pair.
  const std::uint32_t* const pair_j = q.j.data();
  auto j_side = [&](const double* p, const double* const* roll, std::size_t k, std::size_t b) {
    const std::uint32_t j = pair_j[k];
    if (j < own_begin) [[unlikely]] {  // another thread's particle: left for its owner
      leave(j, p, roll, b);
      return;
    }
    subtract_j_side<kRolling>(acc + kAccStride * j, p, kin[kKinStride * j + 3], roll, b);
  };
  assign_rows<kRolling>(q, first, last, blk, kin, acc, j_side);
}

// The j sides a later thread left (accumulate_ordered), subtracted in the order they were left.
template <bool kRolling>
inline void add_left_sides(const double* kin, const LeftJSides& left, double* acc) {
  const double* roll[3] = {left.roll_x.data(), left.roll_y.data(), left.roll_z.data()};
  for (std::size_t at = 0; at < left.count; ++at) {
    const std::uint32_t j = left.j[at];
    subtract_j_side<kRolling>(acc + kAccStride * j, left.records.data() + kLanes * at,
                              kin[kKinStride * j + 3], roll, at);
  }
}

// Where thread t of `threads` begins its rows, and its particles in the drift: from `bounds`
// (RowRanges: threads + 1 starts, each a whole lane group, so that every thread's eight-lane
// loads and stores of the particle arrays start on a cache line) where it has one per thread,
// else n t / T rounded down to a whole lane group. Where a range starts changes no bit.
inline std::size_t range_begin(std::span<const std::size_t> bounds, std::size_t n, std::size_t t,
                               std::size_t threads) {
  if (bounds.size() == threads + 1 && bounds.back() == n) return bounds[t];
  return t >= threads ? n : n * t / threads / kLanes * kLanes;
}

// Rows per block of the ordered pass. Not kRowsPerBlock: no schedule deals these out (each
// thread takes one range), and on the bed at one thread blocks of 512 rows ran the step 1.08x
// (AVX-512) and 1.06x (AVX2) faster than blocks of 64, 256 about as fast, 1024 and 2048 at 0.98
// and 0.96 of 512 (interleaved, 9 - 13 rounds, three runs): a block's fixed costs (a call of the
// pair kernel and of the finish, the finish's clock reads, the sums' setup) weigh more than its
// records' staying in L1 (sub-blocks of 64 or 128 rows for the pairs and sums inside a block of
// 512: 0.97 and 1.00).
constexpr std::size_t kOrderedBlockRows = 512;

// The force pass: each thread takes a contiguous range of rows [b, e) (range_begin), computes them
// a block at a time (pair_rows, accumulate_ordered) and finishes particles [a, z) (finish(a, z,
// with_walls, large, bad_wall): walls unless serial_walls, when walls(0, n, ...) adds them for
// every particle in one thread first; gravity, kick) as soon as the rows holding its j sides, (a, a
// + lag], are done; lag = max_span finishes particles while their sums are still in cache (fused),
// lag = n finishes the rest after the rows (split). mark(phase) is called by every thread where a
// phase ends (after the pairs, the j sides from other threads, the serial walls). The last
// max_span particles of a range wait for the rows that reach them: those of the later threads
// whose ranges start within max_span of its end (done: their signals of pass `pass`; with serial
// walls, a barrier of the team); the others are finished before the wait. A particle's sums do
// not depend on when it is finished, so the result is the same for any thread count and any
// ranges. With more than one thread each reports busy(t, seconds) on its own range (its pairs,
// the j sides left to it and its finish; not the waits nor the serial walls), for RowRanges to
// even out.
template <bool kRolling, bool kClamp, class Finish, class Walls, class Mark, class Busy>
void force_pass(const double* kin, std::size_t n, PairList& q, const PairCoefficients& c, double dt,
                bool fused, bool serial_walls, std::span<const std::size_t> bounds, double* acc,
                std::vector<double>& scratch, std::span<LeftJSides> left, RowsDone& done,
                std::uint64_t pass, Finish& finish, Walls& walls, Mark& mark, Busy& busy,
                std::uint64_t& large, std::uint32_t& bad_pair, std::uint32_t& bad_wall) {
  const auto t = static_cast<std::size_t>(omp_get_thread_num());
  const auto threads = static_cast<std::size_t>(omp_get_num_threads());
  const std::size_t b = range_begin(bounds, n, t, threads);
  const std::size_t e = range_begin(bounds, n, t + 1, threads);
  // left[from * threads + owner]: the j sides thread `from` leaves for `owner` (threads^2 lists,
  // the caller's, kept from step to step); this thread's own were read in the last step.
  for (std::size_t owner = 0; owner < t; ++owner) left[t * threads + owner].count = 0;
  auto left_for = [&](std::uint32_t j) -> LeftJSides& {
    std::size_t owner = t - 1;  // j < b: an earlier thread's, mostly the one just before
    while (j < range_begin(bounds, n, owner, threads)) --owner;
    return left[t * threads + owner];
  };
  const bool timed = threads > 1;
  const double start_s = timed ? omp_get_wtime() : 0.0;
  const std::size_t lag = fused ? q.max_span : n;
  std::uint64_t large_here = 0;
  std::uint32_t bad_here = UINT32_MAX, bad_wall_here = UINT32_MAX;
  PairBlock blk(scratch);
  std::size_t next = b;  // the next particle to finish
  for (std::size_t first = b; first < e; first += kOrderedBlockRows) {
    const std::size_t last = std::min(e, first + kOrderedBlockRows);
    pair_rows<kRolling, kClamp>(kin, q, c, dt, first, last, SpringsTo::kList, blk, large_here,
                                bad_here);
    accumulate_ordered<kRolling>(kin, q, first, last, blk, b, acc, left_for);
    if (next + lag < last) {
      // Known to the finish, which then drifts nothing: a failed run's message shows a failed
      // pair's particles where this step found them.
      if (bad_here != UINT32_MAX) {
        combine_counts(large_here, bad_here, large, bad_pair);
        large_here = 0;
        bad_here = UINT32_MAX;
      }
      finish(next, last - lag, true, large_here, bad_wall_here);
      next = last - lag;
    }
  }
  // The pairs' failures before the signal: a finish after the wait knows those of the rows that
  // reach its particles.
  combine_counts(large_here, bad_here, large, bad_pair);
  large_here = 0;
  // The later threads whose rows reach this range: [t + 1, reaching). A later one's pair (i, j)
  // has j >= i - max_span, so one starting at or past e + max_span leaves nothing here and
  // reads no block here (and is not waited for: it may still be starting, resetting its lists).
  std::size_t reaching = t + 1;
  while (reaching < threads && range_begin(bounds, n, reaching, threads) < e + q.max_span) {
    ++reaching;
  }
  // Before the wait, the particles no later thread's rows reach, [next, e - max_span): their
  // sums are complete, no other thread reads their blocks in this pass (so the drift may
  // rewrite them), and a failed pair of theirs is one of this thread's, combined above. Why:
  // a range whose finish weighs more than the next range's (the bed's floor contacts lie in the
  // first) waited for the next thread's rows, and that one then waited at the pass's end for
  // this finish (at two threads on the bed about 130 us each, 7 % of a step).
  if (!serial_walls && reaching > t + 1 && next + q.max_span < e) {
    mark(Phase::kEarlyFinishBegin);
    finish(next, e - q.max_span, true, large_here, bad_wall_here);
    next = e - q.max_span;
    mark(Phase::kEarlyFinishEnd);
  }
  double busy_s = timed ? omp_get_wtime() - start_s : 0.0;
  if (serial_walls) {
#pragma omp barrier
  } else {
    done.announce(t, pass);
    for (std::size_t u = t + 1; u < reaching; ++u) done.wait_for(u, pass);
  }
  mark(Phase::kPairs);
  const double resume_s = timed ? omp_get_wtime() : 0.0;
  // The j sides later threads left, in their order (their rows' order): none from a particle
  // finished above, whose j sides all came from this thread's rows.
  for (std::size_t from = t + 1; from < reaching; ++from) {
    add_left_sides<kRolling>(kin, left[from * threads + t], acc);
  }
  busy_s += timed ? omp_get_wtime() - resume_s : 0.0;
  mark(Phase::kReduction);
  if (serial_walls) {  // every particle's pairs are in (fused is off: no one finished yet)
#pragma omp barrier
#pragma omp single
    walls(0, n, large_here, bad_wall_here);
    mark(Phase::kWalls);
  }
  const double finish_s = timed ? omp_get_wtime() : 0.0;
  if (next < e) finish(next, e, !serial_walls, large_here, bad_wall_here);
  combine_counts(large_here, bad_wall_here, large, bad_wall);
  if (timed) busy(t, busy_s + (omp_get_wtime() - finish_s));
}

// body(first, last) for the particles [first, last) of each block of kRowsPerBlock, the
// blocks shared out by the variant's schedule (`omp for schedule(runtime) nowait`: the caller
// sets the schedule and places the barrier).
template <class Body>
inline void for_each_block(std::size_t n, Body&& body) {
  const std::size_t blocks = (n + kRowsPerBlock - 1) / kRowsPerBlock;
#pragma omp for schedule(runtime) nowait
  for (std::size_t block = 0; block < blocks; ++block) {
    const std::size_t first = block * kRowsPerBlock;
    body(first, std::min(n, first + kRowsPerBlock));
  }
}

// The update (finish(first, last, with_walls, ...)) over the same blocks of particles as the pairs,
// by the variant's schedule (a chunk of k is k blocks in both loops; per particle, dynamic,1 would
// pay a scheduling round trip per particle).
template <class Finish>
inline void update_blocks(std::size_t n, bool serial_walls, Finish& finish,
                          std::uint64_t& large_here, std::uint32_t& bad_wall_here) {
  for_each_block(n, [&](std::size_t first, std::size_t last) {
    finish(first, last, !serial_walls, large_here, bad_wall_here);
  });
#pragma omp barrier
}

// Adds a value to a shared sum: atomically (kAtomic: threads may add to the same particle)
// or plainly (a per-thread array).
template <bool kAtomic>
inline void add_to(double& sum, double value) {
  if constexpr (kAtomic) {
#pragma omp atomic
    sum += value;
  } else {
    sum += value;
  }
}

// The block's outputs added to `target` (a thread's own array, or with kAtomic the shared
// one): i's row summed in registers, then added; each j side subtracted.
template <bool kRolling, bool kAtomic>
inline void accumulate_shared(const double* kin, const PairList& q, std::size_t first,
                              std::size_t last, PairBlock& blk, double* target) {
  auto j_side = [&](const double* p, const double* const* roll, std::size_t k, std::size_t b) {
    const std::uint32_t j = q.j[k];
    const double rj = kin[kKinStride * j + 3];
    double* aj = target + kAccStride * j;
    for (int d = 0; d < 3; ++d) {
      const double rolling = kRolling ? roll[d][b] : 0.0;
      add_to<kAtomic>(aj[d], -p[PairBlock::kFx + d]);
      add_to<kAtomic>(aj[3 + d], -(rj * p[PairBlock::kCx + d]) - rolling);
    }
    add_to<kAtomic>(aj[6], p[PairBlock::kTouch]);
  };
  auto add_row = [&](std::size_t i, const Lanes& sum) {
    double* ai = target + kAccStride * i;
    for (int f = 0; f < 7; ++f) add_to<kAtomic>(ai[f], sum[f]);
  };
  sum_rows<kRolling>(q, first, last, blk, kin, j_side, add_row);
}

// The force pass of the non-ordered accumulations (per-thread arrays, atomics): blocks of rows
// shared out by the variant's schedule (`omp for schedule(runtime)`: the caller sets it), then
// the per-thread arrays summed in thread order, the walls by one thread when serial_walls, and
// the update (finish(first, last, with_walls, ...)) over the same blocks by the same schedule.
template <bool kRolling, bool kClamp, class Finish, class Walls, class Mark>
void force_pass_shared(const double* kin, std::size_t n, PairList& q, const PairCoefficients& c,
                       double dt, bool atomic, bool serial_walls, double* acc,
                       std::vector<AlignedVector<double>>& thread_acc, std::vector<double>& scratch,
                       Finish& finish, Walls& walls, Mark& mark, std::uint64_t& large,
                       std::uint32_t& bad_pair, std::uint32_t& bad_wall) {
  const auto t = static_cast<std::size_t>(omp_get_thread_num());
  const auto threads = static_cast<std::size_t>(omp_get_num_threads());
  std::uint64_t large_here = 0;
  std::uint32_t bad_here = UINT32_MAX, bad_wall_here = UINT32_MAX;
  double* target = acc;
  if (atomic) {
#pragma omp for schedule(static)
    for (std::size_t a = 0; a < kAccStride * n; ++a) acc[a] = 0.0;
  } else {
    thread_acc[t].assign(kAccStride * n, 0.0);  // the report's cost: one array per thread
    target = thread_acc[t].data();
  }
  PairBlock blk(scratch);
  for_each_block(n, [&](std::size_t first, std::size_t last) {
    pair_rows<kRolling, kClamp>(kin, q, c, dt, first, last, SpringsTo::kList, blk, large_here,
                                bad_here);
    if (atomic) {
      accumulate_shared<kRolling, true>(kin, q, first, last, blk, target);
    } else {
      accumulate_shared<kRolling, false>(kin, q, first, last, blk, target);
    }
  });
  combine_counts(large_here, bad_here, large, bad_pair);  // before the update: see force_pass
  large_here = 0;
#pragma omp barrier
  mark(Phase::kPairs);
  if (!atomic) {  // the reduction, in thread order
#pragma omp for schedule(static)
    for (std::size_t a = 0; a < kAccStride * n; ++a) {
      double sum = thread_acc[0][a];
      for (std::size_t u = 1; u < threads; ++u) sum += thread_acc[u][a];
      acc[a] = sum;
    }
  }
  mark(Phase::kReduction);
  if (serial_walls) {
#pragma omp single
    walls(0, n, large_here, bad_wall_here);
    mark(Phase::kWalls);
  }
  update_blocks(n, serial_walls, finish, large_here, bad_wall_here);
  combine_counts(large_here, bad_wall_here, large, bad_wall);
}

// The full list's i sides: each row's outputs summed in pair order into its particle's sums
// (assigned: nothing else reaches a particle before its own row).
template <bool kRolling>
inline void accumulate_rows(const double* kin, const PairList& q, std::size_t first,
                            std::size_t last, PairBlock& blk, double* acc) {
  assign_rows<kRolling>(q, first, last, blk, kin, acc,
                        [](const double*, const double* const*, std::size_t, std::size_t) {});
}

// The full list's j sides: the block's j-side pairs (pair_gathered of j_pairs[e0 ..)),
// subtracted from their j particle's sums in pair order, as the ordered pass does.
template <bool kRolling>
inline void accumulate_j_sides(const double* kin, const PairList& q, std::size_t first,
                               std::size_t last, PairBlock& blk, double* acc) {
  const std::size_t e0 = q.j_offsets[first];
  const double* rec = blk.records();
  const double* roll[3] = {blk.roll(0), blk.roll(1), blk.roll(2)};
  for (std::size_t a = first; a < last; ++a) {
    const double r = kin[kKinStride * a + 3];
    for (std::size_t e = q.j_offsets[a]; e < q.j_offsets[a + 1]; ++e) {
      const std::size_t b = e - e0;
      subtract_j_side<kRolling>(acc + kAccStride * a, rec + kLanes * b, r, roll, b);
    }
  }
}

// The force pass of the full list (each pair computed twice, once for each side): a block of
// particles computes its own rows (springs of this step in, next step's out to
// PairList::*_next) and then its j sides again from the springs of this step, and writes only
// its own particles' sums: no shared writes, so any schedule, and each particle's sums are its
// own row, then its j sides in pair order, with the same arithmetic as the ordered pass:
// bit-identical to it for any thread count and schedule. update=fused finishes the block's
// particles at once. The caller swaps the springs in after the pass.
template <bool kRolling, bool kClamp, class Finish, class Walls, class Mark>
void force_pass_full(const double* kin, std::size_t n, PairList& q, const PairCoefficients& c,
                     double dt, bool fused, bool serial_walls, double* acc,
                     std::vector<double>& scratch, Finish& finish, Walls& walls, Mark& mark,
                     std::uint64_t& large, std::uint32_t& bad_pair, std::uint32_t& bad_wall) {
  std::uint64_t large_here = 0;
  std::uint32_t bad_here = UINT32_MAX, bad_wall_here = UINT32_MAX;
  PairBlock blk(scratch);
  for_each_block(n, [&](std::size_t first, std::size_t last) {
    const std::size_t e0 = q.j_offsets[first], e1 = q.j_offsets[last];
    pair_rows<kRolling, kClamp>(kin, q, c, dt, first, last, SpringsTo::kNext, blk, large_here,
                                bad_here);
    accumulate_rows<kRolling>(kin, q, first, last, blk, acc);
    pair_gathered<kRolling, kClamp>(kin, q, c, dt, q.j_pairs.data() + e0, e1 - e0, blk);
    accumulate_j_sides<kRolling>(kin, q, first, last, blk, acc);
    if (fused) {
      finish(first, last, true, large_here, bad_wall_here);
    }
  });
  combine_counts(large_here, bad_here, large, bad_pair);  // before the update: see force_pass
  large_here = 0;
#pragma omp barrier
  mark(Phase::kPairs);
  mark(Phase::kReduction);
  if (!fused) {
    if (serial_walls) {
#pragma omp single
      walls(0, n, large_here, bad_wall_here);
      mark(Phase::kWalls);
    }
    update_blocks(n, serial_walls, finish, large_here, bad_wall_here);
  }
  combine_counts(large_here, bad_wall_here, large, bad_wall);
}

}  // CONTACTLAB_DEM_ISA_NAMESPACE(build)
}  // namespace contactlab::dem::detail

#endif
