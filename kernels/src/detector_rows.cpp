// The contact lists' CSR rows, assembled after the traversal by every thread of the detection
// region: the row offsets by a parallel prefix sum, each thread's finds copied to their rows and,
// with the half stencil, each find (h, j) also written to row j as the reverse entry h.
//
// Cost per thread, P threads, N particles, C entries: O(N / P + C / P + P) where the loop's
// schedule balances the finds, and memory O(N + C + P^2) in all, whatever P is. (Counting the
// reverse entries per (thread, row) had been N x P counts, zeroed and scanned: its per-thread
// time did not fall with P, and the half stencil scaled 3.7x on 16 cores.)
#include <omp.h>

#include <algorithm>
#include <cstring>
#include <type_traits>

#include "contactlab/kernels/detector.hpp"

namespace contactlab {

namespace {

// Rows summed into one weight for choose_row_blocks: the boundaries fall on multiples of it.
// 256 rows: N / 256 weights (4,000 on the paper's scene), and at most 256 rows' imbalance.
constexpr std::uint32_t kWeightRows = 256;

// The thread that assembles row j, for rows met in runs: the last block is asked first.
class RowBlockOf {
 public:
  RowBlockOf(const std::uint32_t* bounds, int threads) : bounds_(bounds), threads_(threads) {}
  int operator()(std::uint32_t j) {
    if (j - lo_ >= hi_ - lo_) {
      block_ = static_cast<int>(std::upper_bound(bounds_ + 1, bounds_ + threads_ + 1, j) -
                                (bounds_ + 1));
      lo_ = bounds_[block_];
      hi_ = bounds_[block_ + 1];
    }
    return block_;
  }

 private:
  const std::uint32_t* bounds_;
  int threads_;
  int block_ = 0;
  std::uint32_t lo_ = 0, hi_ = 0;
};

}  // namespace

void ContactDetector::assemble_rows(int tid, int threads, bool half, bool rows_in_blocks) {
  if (half) {
    assemble_half_rows(tid, threads);
    return;
  }
  // The full stencil's rows hold their own finds only: offsets over an equal range of rows each,
  // once every thread has counted its homes' finds.
#pragma omp barrier
  const std::uint32_t n = static_cast<std::uint32_t>(found_count_.size());
  const std::uint32_t first = static_cast<std::uint32_t>(std::uint64_t{n} * tid / threads);
  const std::uint32_t last = static_cast<std::uint32_t>(std::uint64_t{n} * (tid + 1) / threads);
  std::uint64_t* const offsets = contacts_.offsets.data();
  std::uint64_t running = 0;
  for (std::uint32_t i = first; i < last; ++i) {
    running += found_count_[i];
    offsets[i + 1] = running;
  }
  finish_offsets(tid, threads, first, last, running);
  if (rows_in_blocks) {
    copy_row_blocks(tid, threads);
    return;
  }
  // A buffer still borrowing the contact list's storage holds its rows in place (resize keeps
  // them, copying them along if it has to grow).
  const detail::ThreadOutput& mine = thread_out_[tid];
  if (mine.partners.borrowing()) return;
  // A run of consecutive homes (a chunk of the schedule) is one block of the output and one
  // memcpy, not one per home (a call of about 100 bytes each, 1M of them on the paper's scene).
  std::uint32_t* const partners = contacts_.partners.data();
  const std::uint32_t* const finds = mine.partners.data();
  const std::uint32_t* const homes = mine.homes.data();
  const std::size_t home_count = mine.homes.size();
  std::size_t at = 0;
  for (std::size_t k = 0; k < home_count;) {
    const std::uint32_t first_home = homes[k];
    std::size_t next = k + 1;
    while (next < home_count && homes[next] == homes[next - 1] + 1) ++next;
    const std::uint32_t end_home = homes[next - 1] + 1;
    const std::size_t count = offsets[end_home] - offsets[first_home];
    std::memcpy(partners + offsets[first_home], finds + at, count * sizeof(std::uint32_t));
    at += count;
    k = next;
  }
}

// Rows [first, last) are this thread's and their offsets hold the prefix of their sizes from
// `first`, summing to rows_sum: each thread shifts its range by the sums of the ranges before it,
// and the partners get their room.
void ContactDetector::finish_offsets(int tid, int threads, std::uint32_t first, std::uint32_t last,
                                     std::uint64_t rows_sum) {
  range_sums_[tid] = rows_sum;
#pragma omp barrier
  std::uint64_t base = 0;
  for (int t = 0; t < tid; ++t) base += range_sums_[t];
  std::uint64_t* const offsets = contacts_.offsets.data();
  if (base > 0) {
    for (std::uint32_t i = first; i < last; ++i) offsets[i + 1] += base;
  }
  if (tid + 1 == threads) {
    offsets[0] = 0;
    // Address space only: the threads first-touch their rows' pages as they write them.
    contacts_.partners.resize(base + rows_sum);
  }
#pragma omp barrier
}

// Which rows each thread assembles with the half stencil (row_block_). Where every thread's homes
// are one run of consecutive rows, back to back in thread order (a block schedule over sorted
// particles), a thread assembles the rows it was home to: its reverse finds are mostly its own
// rows, and only those across its last boundary go to another thread. Otherwise (chunks, a
// dynamic schedule, unsorted particles) the rows are split by weight, a row weighing its own
// finds (about its reverse entries) plus one, so that a clustered scene's dense rows do not all
// fall to one thread. O(N / P + P) per thread. Returns whether the rows are the homes.
bool ContactDetector::choose_row_blocks(int tid, int threads) {
  const std::uint32_t n = static_cast<std::uint32_t>(found_count_.size());
  const detail::PartnerBuffer& homes = thread_out_[tid].homes;
  const std::size_t count = homes.size();
  const bool one_run = count == 0 || homes.data()[count - 1] - homes.data()[0] + 1 == count;
  const std::size_t slot = 2 * static_cast<std::size_t>(tid);  // this thread's (first, size)
  home_run_[slot] = count == 0 ? 0 : homes.data()[0];
  home_run_[slot + 1] = one_run ? count : UINT32_MAX;  // UINT32_MAX: not one run
#pragma omp barrier
  std::uint64_t next = 0;  // the row after the runs so far
  std::uint32_t mine = 0;  // this thread's first row
  bool back_to_back = true;
  for (int t = 0; t < threads && back_to_back; ++t) {
    const std::size_t run = 2 * static_cast<std::size_t>(t);
    const std::uint64_t first = home_run_[run], size = home_run_[run + 1];
    if (t == tid) mine = static_cast<std::uint32_t>(next);
    if (size == 0) continue;
    back_to_back = size != UINT32_MAX && first == next;
    next = first + size;
  }
  if (back_to_back && next <= n) {
    row_block_[tid] = tid == 0 ? 0 : mine;
    if (tid + 1 == threads) row_block_[threads] = n;
#pragma omp barrier
    return true;
  }
  // By weight: this thread sums an equal share of the kWeightRows-row groups, the shares are
  // scanned, and each thread finds its first row where the running weight reaches its share.
  const std::uint32_t groups = (n + kWeightRows - 1) / kWeightRows;
  const std::uint32_t first_group =
      static_cast<std::uint32_t>(std::uint64_t{groups} * tid / threads);
  const std::uint32_t last_group =
      static_cast<std::uint32_t>(std::uint64_t{groups} * (tid + 1) / threads);
#pragma omp single
  row_weight_.resize(std::size_t{groups} + 1);  // the running weight before each group
  std::uint64_t* const weight = row_weight_.data();
  std::uint64_t running = 0;
  for (std::uint32_t g = first_group; g < last_group; ++g) {
    const std::uint32_t row_end = std::min(n, (g + 1) * kWeightRows);
    for (std::uint32_t j = g * kWeightRows; j < row_end; ++j) running += found_count_[j] + 1;
    weight[g + 1] = running;
  }
  range_sums_[tid] = running;
#pragma omp barrier
  std::uint64_t base = 0, total = 0;
  for (int t = 0; t < threads; ++t) {
    if (t < tid) base += range_sums_[t];
    total += range_sums_[t];
  }
  for (std::uint32_t g = first_group; g < last_group; ++g) weight[g + 1] += base;
  if (tid == 0) weight[0] = 0;
#pragma omp barrier
  const std::uint64_t share = total / threads * tid + total % threads * tid / threads;
  const std::uint64_t group = std::lower_bound(weight, weight + groups + 1, share) - weight;
  row_block_[tid] = static_cast<std::uint32_t>(std::min<std::uint64_t>(n, group * kWeightRows));
  if (tid + 1 == threads) row_block_[threads] = n;
#pragma omp barrier
  return false;
}

// The previous thread's finds for this thread's rows [lo, hi), as (row, home) pairs in its finding
// order, read from where its own rows end (which it publishes as soon as it knows, early in its
// count). Its homes are one run of consecutive rows: home k's finds follow home k - 1's.
void ContactDetector::take_from_previous(int tid, std::uint32_t lo, std::uint32_t hi) {
  const detail::ThreadOutput& previous = thread_out_[tid - 1];
  std::uint64_t from;
  while ((from = own_until_[tid - 1].load(std::memory_order_acquire)) == kOwnUntilUnknown) {
#if defined(__x86_64__)
    __builtin_ia32_pause();
#endif
  }
  const std::uint32_t* const finds = previous.partners.data();
  const std::size_t find_count = previous.partners.size();
  if (from >= find_count) return;
  const std::uint32_t* const homes = previous.homes.data();
  const std::uint32_t* const found = found_count_.data();
  detail::PartnerBuffer& taken = thread_out_[tid].taken;
  std::size_t k = 0, home_end = found[homes[0]];
  for (std::size_t at = from; at < find_count; ++at) {
    const std::uint32_t j = finds[at];
    if (j - lo >= hi - lo) continue;
    while (at >= home_end) home_end += found[homes[++k]];
    std::uint32_t* const pair = taken.tail(2);
    pair[0] = j;
    pair[1] = homes[k];
    taken.advance(2);
  }
}

// Row j = j's own finds, then every find (h, j) made from another particle h: first those of the
// thread assembling row j (from its own buffer), then those the other threads passed it, thread
// by thread. A thread counts the reverse entries of its own rows as it reads its finds and passes
// the others on grouped by the thread whose rows they are, so no count is kept per (thread, row);
// where the rows are the homes, those for the next thread's rows that one takes itself
// (take_from_previous), in the same place of the order.
void ContactDetector::assemble_half_rows(int tid, int threads) {
  const bool rows_are_homes = choose_row_blocks(tid, threads);
  detail::ThreadOutput& mine = thread_out_[tid];
  const std::uint32_t lo = row_block_[tid], hi = row_block_[tid + 1];
  std::uint32_t* const reverse = reverse_count_.data();
  std::fill(reverse + lo, reverse + hi, 0u);
  const std::uint32_t* const finds = mine.partners.data();
  const std::uint32_t* const homes = mine.homes.data();
  const std::size_t home_count = mine.homes.size();
  const std::uint32_t* const found = found_count_.data();
  auto own_row = [lo, span = hi - lo](std::uint32_t j) { return j - lo < span; };
  // One thread's block of every row (one thread): no row to ask about, none to pass on.
  const bool all_rows = lo == 0 && hi == found_count_.size();

  // Count this thread's reverse entries of its own rows in one flat pass over its finds (a pass
  // home by home, each home's few finds a loop of its own, made the one-thread assembly a
  // quarter slower: its exits mispredict). A find for another thread's row becomes a (row, home)
  // pair at once, its home found by walking the homes' find counts alongside (the spills come in
  // finding order, so the walk is one pass over the homes in all).
  mine.spills.clear();
  std::vector<std::uint64_t>& spill_begin = mine.spill_begin;
  spill_begin.assign(threads + 1, 0);
  RowBlockOf block_of(row_block_.data(), threads);
  const std::size_t find_count = mine.partners.size();
  // The finds before own_until are all for this thread's rows: the write pass needs no check
  // there. Under a block schedule of sorted particles, thread 0 of two on the paper scene finds
  // its first spill 61 % of the way through its finds, and the last thread none (the checks on
  // every find had cost the two-thread half stencil's assembly 4 ms of its 31).
  //
  // Where the rows are the homes, a thread's finds for the next thread's rows come at the end of
  // its own, mixed with them (its dense last cells reach into the next thread's first ones).
  // The next thread takes those itself from this thread's buffer (take_from_previous), from
  // where this thread publishes that its own rows end, while this thread counts on: so the
  // thread whose rows end in the scene's dense centre no longer also records a spill for each of
  // them (thread 0 of two on the paper scene had counted for 5.9 ms while thread 1 waited 3.5).
  std::size_t own_until = find_count;
  const std::uint32_t next_lo = hi,
                      next_hi = rows_are_homes && tid + 1 < threads ? row_block_[tid + 2] : hi;
  auto next_row = [next_lo, span = next_hi - next_lo](std::uint32_t j) {
    return j - next_lo < span;
  };
  if (all_rows) {
    for (std::size_t at = 0; at < find_count; ++at) ++reverse[finds[at]];
    if (rows_are_homes) own_until_[tid].store(find_count, std::memory_order_release);
  } else {
    std::size_t at = 0;
    for (; at < find_count && own_row(finds[at]); ++at) ++reverse[finds[at]];
    own_until = at;
    if (rows_are_homes) own_until_[tid].store(own_until, std::memory_order_release);
    std::size_t k = 0, home_end = home_count > 0 ? found[homes[0]] : 0;
    for (; at < find_count; ++at) {
      const std::uint32_t j = finds[at];
      if (own_row(j)) [[likely]] {
        ++reverse[j];
      } else if (!next_row(j)) {
        while (at >= home_end) home_end += found[homes[++k]];
        std::uint32_t* const pair = mine.spills.tail(2);
        pair[0] = j;
        pair[1] = homes[k];
        mine.spills.advance(2);
        ++spill_begin[block_of(j) + 1];
      }
    }
  }
  mine.taken.clear();
  if (rows_are_homes && tid > 0 && lo < hi) take_from_previous(tid, lo, hi);
  // Grouped by the assembling thread (a counting sort: groups in thread order, pairs in finding
  // order within a group), unless one thread takes them all (always so at two threads): then
  // the finding order is the grouped one, and the pairs are read where they are (spilled_pairs).
  if (const std::size_t spilled = mine.spills.size(); spilled > 0) {
    const bool one_group = std::any_of(spill_begin.begin() + 1, spill_begin.end(),
                                       [&](std::uint64_t c) { return 2 * c == spilled; });
    for (int t = 0; t < threads; ++t) spill_begin[t + 1] += spill_begin[t];
    if (!one_group) {
      mine.spills_by_row_block.resize(spilled);
      std::vector<std::uint64_t> next(spill_begin.begin(), spill_begin.end() - 1);
      const std::uint32_t* const pairs = mine.spills.data();
      std::uint32_t* const grouped = mine.spills_by_row_block.data();
      for (std::size_t p = 0; p < spilled; p += 2) {
        const std::uint64_t to = 2 * next[block_of(pairs[p])]++;
        grouped[to] = pairs[p];
        grouped[to + 1] = pairs[p + 1];
      }
    }
  }
#pragma omp barrier
  // The reverse entries the other threads passed this one.
  auto passed = [&](auto&& f) {
    for (int u = 0; u < threads; ++u) {
      if (u + 1 == tid) {  // what this thread took from the previous one (if any)
        const std::uint32_t* const pairs = mine.taken.data();
        for (std::size_t p = 0; p < mine.taken.size(); p += 2) f(pairs[p], pairs[p + 1]);
      }
      const detail::ThreadOutput& from = thread_out_[u];
      if (u == tid || from.spills.size() == 0) continue;
      const std::uint64_t spilled = from.spill_begin[threads];
      // One group: the spills in finding order (assemble_half_rows skipped the grouping).
      const bool one_group = from.spill_begin[tid + 1] - from.spill_begin[tid] == spilled;
      const std::uint32_t* const pairs =
          one_group ? from.spills.data() : from.spills_by_row_block.data();
      for (std::uint64_t p = from.spill_begin[tid]; p < from.spill_begin[tid + 1]; ++p)
        f(pairs[2 * p], pairs[2 * p + 1]);
    }
  };
  passed([&](std::uint32_t j, std::uint32_t) { ++reverse[j]; });
  // Offsets of this thread's rows; reverse[j] becomes where row j's next reverse entry goes.
  std::uint64_t* const offsets = contacts_.offsets.data();
  std::uint64_t running = 0;
  for (std::uint32_t j = lo; j < hi; ++j) {
    running += found[j] + reverse[j];
    reverse[j] = found[j];
    offsets[j + 1] = running;
  }
  finish_offsets(tid, threads, lo, hi, running);

  // This thread's finds to their rows, and the reverse entries of its own rows. These land about
  // a z-layer of cells ahead, megabytes beyond L2 on a dense scene: each target line is fetched
  // for writing kAhead finds early, so the misses overlap (64 ran the half stencil 5 - 15 %
  // faster than 16 on the paper and core scenes).
  constexpr std::size_t kAhead = 64;
  std::uint32_t* const partners = contacts_.partners.data();
  const std::size_t total = mine.partners.size();
  auto write_reverse = [&](std::uint32_t h, std::size_t at, std::size_t end, auto checked) {
    constexpr bool kChecked = decltype(checked)::value;
    for (; at < end; ++at) {
      if (at + kAhead < total) {
        const std::uint32_t ahead = finds[at + kAhead];
        if (!kChecked || own_row(ahead))
          __builtin_prefetch(partners + offsets[ahead] + reverse[ahead], 1);
      }
      const std::uint32_t j = finds[at];
      if (!kChecked || own_row(j)) partners[offsets[j] + reverse[j]++] = h;
    }
  };
  std::size_t at = 0;
  for (std::size_t k = 0; k < home_count; ++k) {
    const std::uint32_t h = homes[k];
    const std::uint32_t count = found[h];
    if (count == 0) continue;
    std::memcpy(partners + offsets[h], finds + at, count * sizeof(std::uint32_t));
    const std::size_t end = at + count;
    if (end + kAhead <= own_until) {
      write_reverse(h, at, end, std::false_type{});
    } else {
      write_reverse(h, at, end, std::true_type{});
    }
    at = end;
  }
  passed([&](std::uint32_t j, std::uint32_t h) { partners[offsets[j] + reverse[j]++] = h; });
}

// Where each thread's homes are consecutive rows (the full stencil under a static schedule
// without a chunk size: see writes_first_rows_in_place), each thread's buffer is one block of
// the output, starting at its first home's row. The blocks not written in place are copied by
// every thread, an equal slice each: thread 0 writes in place and had nothing to copy, so
// copying one's own rows left it idle while the others copied (at two threads, a quarter of the
// output's time on one thread alone).
void ContactDetector::copy_row_blocks(int tid, int threads) {
  std::uint64_t total = 0;
  for (int u = 0; u < threads; ++u) {
    if (!thread_out_[u].partners.borrowing()) total += thread_out_[u].partners.size();
  }
  const std::uint64_t mine_first = total * tid / threads, mine_last = total * (tid + 1) / threads;
  std::uint64_t block_first = 0;  // of block u, in the concatenation of the copied blocks
  for (int u = 0; u < threads && block_first < mine_last; ++u) {
    const detail::ThreadOutput& block = thread_out_[u];
    if (block.partners.borrowing() || block.partners.size() == 0) continue;
    const std::uint64_t block_last = block_first + block.partners.size();
    const std::uint64_t first = std::max(block_first, mine_first);
    const std::uint64_t last = std::min(block_last, mine_last);
    if (first < last) {
      const std::uint64_t row_start = contacts_.offsets[block.homes.data()[0]];
      std::memcpy(contacts_.partners.data() + row_start + (first - block_first),
                  block.partners.data() + (first - block_first),
                  (last - first) * sizeof(std::uint32_t));
    }
    block_first = block_last;
  }
}

ContactDetector::BufferBytes ContactDetector::buffer_bytes() const {
  BufferBytes bytes;
  auto add = [&](const auto& buffer) { bytes.total += buffer.size() * sizeof(*buffer.data()); };
  for (const detail::ThreadOutput& out : thread_out_) {
    add(out.partners);
    add(out.homes);
    add(out.block_rows);
    add(out.spill_begin);
    bytes.spill_bytes += (out.spills.size() + out.spills_by_row_block.size() + out.taken.size()) *
                         sizeof(std::uint32_t);
  }
  bytes.total += bytes.spill_bytes;
  add(found_count_);
  add(reverse_count_);
  add(row_block_);
  add(home_run_);
  add(row_weight_);
  add(range_sums_);
  add(contacts_.offsets);
  add(contacts_.partners);
  bytes.total += registry_.buffer_bytes();
  add(working_.x);
  add(working_.y);
  add(working_.z);
  add(working_.diameter);
  add(narrow_x_);
  add(narrow_y_);
  add(narrow_z_);
  add(narrow_d_);
  return bytes;
}

}  // namespace contactlab
