// The pair list's arrays and CSR index (orientation, rows by i, j sides), and the stable radix
// sort of indices they are grouped by: every pass on the caller's threads.
#include <omp.h>

#include <algorithm>
#include <bit>
#include <utility>

#include "contactlab/dem/pair_list.hpp"  // PairList, RadixBuffers, radix_sort

namespace contactlab::dem {

void PairList::resize_to_overwrite(std::size_t n) {
  dem::resize_to_overwrite(i, n);
  dem::resize_to_overwrite(j, n);
  dem::resize_to_overwrite(image, n);
  for (auto* v : {&hx, &hy, &hz}) dem::resize_to_overwrite(*v, n);
}

namespace {
// v resized to n, its contents kept, with the eighth to spare that resize_to_overwrite leaves: a
// list read from a checkpoint or restored came exactly sized, and the rebuilds swap its arrays
// with their buffers, so each of them reallocated and faulted in again at the first rebuild
// whose list was a few pairs longer (6 - 20 ms each in the settled bed's first rebuilds).
template <class T, class Allocator>
void resize_with_spare(std::vector<T, Allocator>& v, std::size_t n) {
  if (v.capacity() < with_spare(n)) v.reserve(with_spare(n));
  v.resize(n);
}
}  // namespace

void PairList::resize(std::size_t n) {
  resize_with_spare(i, n);
  resize_with_spare(j, n);
  resize_with_spare(image, n);
  for (auto* v : {&hx, &hy, &hz}) resize_with_spare(*v, n);
}

namespace {

// offsets[p] for p in [0, particles]: the first k with keys[k] >= p, for keys ascending and below
// `particles`. Each k writes the offsets in (keys[k - 1], keys[k]], so the threads write apart.
template <class Key>
void offsets_of_sorted(const Key* keys, std::size_t count, std::size_t particles,
                       std::uint32_t* offsets, int threads) {
#pragma omp parallel for schedule(static) num_threads(threads)
  for (std::size_t k = 0; k <= count; ++k) {
    const std::size_t from = k == 0 ? 0 : static_cast<std::size_t>(keys[k - 1]) + 1;
    const std::size_t to = k == count ? particles : static_cast<std::size_t>(keys[k]);
    for (std::size_t p = from; p <= to; ++p) offsets[p] = static_cast<std::uint32_t>(k);
  }
}

// buffers.payload: the indices 0..by.size() ordered by `by` (stable); buffers.keys: `by` so
// ordered.
void stable_order(const std::vector<std::uint32_t>& by, int bits, int threads,
                  RadixBuffers& buffers) {
  const std::size_t count = by.size();
  resize_to_overwrite(buffers.keys, count);
  resize_to_overwrite(buffers.payload, count);
#pragma omp parallel for schedule(static) num_threads(threads)
  for (std::size_t k = 0; k < count; ++k) {
    buffers.keys[k] = by[k];
    buffers.payload[k] = static_cast<std::uint32_t>(k);
  }
  radix_sort(buffers.keys, buffers.payload, bits, buffers.key_scratch, buffers.payload_scratch,
             threads);
}

// v[k] becomes v[order[k]], gathered on `threads` threads into `scratch`, which it swaps with.
template <class T, class Allocator>
void gather(std::vector<T, Allocator>& v, std::vector<T, Allocator>& scratch,
            const std::vector<std::uint32_t>& order, int threads) {
  resize_to_overwrite(scratch, v.size());
#pragma omp parallel for schedule(static) num_threads(threads)
  for (std::size_t k = 0; k < order.size(); ++k) scratch[k] = v[order[k]];
  v.swap(scratch);
}

}  // namespace

void PairList::build_csr(std::size_t particles) {
  RadixBuffers buffers;
  build_csr(particles, 1, buffers);
}

void PairList::build_csr(std::size_t particles, int threads, RadixBuffers& buffers) {
  const std::size_t count = size();
  // Orient every pair from the later particle to the earlier one (j < i), so that particle a's
  // j sides all come from the rows (a, a + max_span]: the fused force pass gathers a as soon as
  // those rows are done. A swapped pair's spring is seen from the other side (negated) and its
  // image shift is negated (code 26 - code).
#pragma omp parallel for schedule(static) num_threads(threads)
  for (std::size_t k = 0; k < count; ++k) {
    if (j[k] > i[k]) {
      std::swap(i[k], j[k]);
      image[k] = static_cast<std::uint8_t>(26 - image[k]);
      hx[k] = -hx[k];
      hy[k] = -hy[k];
      hz[k] = -hz[k];
    }
  }
  bool sorted = true;
#pragma omp parallel for schedule(static) num_threads(threads) reduction(&& : sorted)
  for (std::size_t k = 1; k < count; ++k) sorted = sorted && i[k - 1] <= i[k];
  const int index_bits = std::max(1, static_cast<int>(std::bit_width(particles)));
  // Rows: grouped by i, ascending, each row's pairs in their order (a stable sort by i where the
  // orientation broke it).
  if (!sorted) {
    stable_order(i, index_bits, threads, buffers);
    const std::vector<std::uint32_t>& order = buffers.payload;
    gather(i, buffers.payload_scratch, order, threads);
    gather(j, buffers.payload_scratch, order, threads);
    gather(image, buffers.byte_scratch, order, threads);
    gather(hx, buffers.real_scratch, order, threads);
    gather(hy, buffers.real_scratch, order, threads);
    gather(hz, buffers.real_scratch, order, threads);
  }
  index_rows(particles, threads);
}

void PairList::index_rows(std::size_t particles, int threads) {
  const std::size_t count = size();
  rows.resize(particles + 1);
  offsets_of_sorted(i.data(), count, particles, rows.data(), threads);
  std::size_t span = 0;
#pragma omp parallel for schedule(static) num_threads(threads) reduction(max : span)
  for (std::size_t k = 0; k < count; ++k) span = std::max<std::size_t>(span, i[k] - j[k]);
  max_span = span;
  j_sides_indexed = false;
}

void PairList::index_j_sides(std::size_t particles, int threads, RadixBuffers& buffers) {
  const std::size_t count = size();
  const int index_bits = std::max(1, static_cast<int>(std::bit_width(particles)));
  // The pairs where each particle is the j, in pair order.
  stable_order(j, index_bits, threads, buffers);
  j_pairs.swap(buffers.payload);
  j_offsets.resize(particles + 1);
  offsets_of_sorted(buffers.keys.data(), count, particles, j_offsets.data(), threads);
  j_sides_indexed = true;
}

void radix_sort(std::vector<std::uint64_t>& keys, std::vector<std::uint32_t>& payload, int bits,
                std::vector<std::uint64_t>& key_scratch,
                std::vector<std::uint32_t>& payload_scratch, int threads) {
  // Eight bits a pass: with eleven (one pass fewer on the bed's 34-bit spring keys) the
  // scatter wrote to 2,048 buckets of keys and 2,048 of payloads at once, more lines than L1
  // holds, and sorting the bed's 245,760 new keys took 8.3 ms at one thread, 1.8 ms with 256.
  constexpr int kDigit = 8;
  constexpr std::size_t kBuckets = std::size_t{1} << kDigit;
  const std::size_t n = keys.size();
  resize_to_overwrite(key_scratch, n);
  resize_to_overwrite(payload_scratch, n);
  // At most a thread for every 16 buckets' worth of entries: each thread's counts cost kBuckets.
  const int team = static_cast<int>(
      std::clamp<std::size_t>(n / (16 * kBuckets), 1, static_cast<std::size_t>(threads)));
  std::vector<std::uint64_t> counts(kBuckets * static_cast<std::size_t>(team));
  for (int shift = 0; shift < bits; shift += kDigit) {
    const std::uint64_t* const in_keys = keys.data();
    const std::uint32_t* const in_payload = payload.data();
    std::uint64_t* const out_keys = key_scratch.data();
    std::uint32_t* const out_payload = payload_scratch.data();
    auto digit = [shift](std::uint64_t key) { return (key >> shift) & (kBuckets - 1); };
#pragma omp parallel num_threads(team)
    {
      const auto t = static_cast<std::size_t>(omp_get_thread_num());
      const auto size = static_cast<std::size_t>(omp_get_num_threads());
      const std::size_t first = n * t / size, last = n * (t + 1) / size;
      std::uint64_t* const mine = counts.data() + t * kBuckets;
      std::fill(mine, mine + kBuckets, 0);
      for (std::size_t k = first; k < last; ++k) ++mine[digit(in_keys[k])];
#pragma omp barrier
#pragma omp single
      {  // where each (bucket, thread) starts: bucket by bucket, thread by thread (stable)
        std::uint64_t running = 0;
        for (std::size_t bucket = 0; bucket < kBuckets; ++bucket) {
          for (std::size_t u = 0; u < size; ++u) {
            running += std::exchange(counts[u * kBuckets + bucket], running);
          }
        }
      }  // implicit barrier
      for (std::size_t k = first; k < last; ++k) {
        const std::uint64_t at = mine[digit(in_keys[k])]++;
        out_keys[at] = in_keys[k];
        out_payload[at] = in_payload[k];
      }
    }
    keys.swap(key_scratch);
    payload.swap(payload_scratch);
  }
}

}  // namespace contactlab::dem
