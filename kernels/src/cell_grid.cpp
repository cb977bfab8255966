#include "contactlab/kernels/cell_grid.hpp"

#include <omp.h>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <algorithm>
#include <array>
#include <atomic>
#include <string>
#include <utility>

#include "contactlab/kernels/error.hpp"

namespace contactlab {

CellGrid::CellGrid(const Box& box, double min_width, CellNumbering numbering)
    : numbering_(numbering) {
  if (!(min_width > 0.0) || !std::isfinite(min_width)) {
    throw InputError("cell width (diameter D) must be a positive finite number, got " +
                     number_text(min_width));
  }
  const int axis_limit = numbering == CellNumbering::kLinear ? kMaxAxisCells : kMaxMortonAxisCells;
  double cells = 1.0;
  for (int axis = 0; axis < 3; ++axis) {
    const double extent = box.extent(axis);
    // Widen the cell a little beyond D so that two particles at distance D (give or take the
    // rounding of the contact test) can never be found two cells apart: the cell coordinate
    // floor((x - lo) / w) carries a rounding error of a few ulps of (x - lo) / w and of
    // |x| / w, so the widening grows with the cell count and the distance from the origin.
    const double cells_estimate = extent / min_width;
    const double origin_scale =
        std::max(std::abs(box.lo[axis]), std::abs(box.hi[axis])) / min_width;
    const double widening = std::max(0x1.0p-40, 0x1.0p-46 * (cells_estimate + origin_scale));
    const double width = min_width * (1.0 + widening);
    const double per_axis = std::floor(extent / width);
    if (per_axis > double(axis_limit)) {
      throw InputError("cell grid too large: D = " + number_text(min_width) +
                       " is too small for the box (more than " + std::to_string(axis_limit) +
                       " cells along one axis" +
                       (numbering == CellNumbering::kMorton ? " with Morton numbering)" : ")"));
    }
    dims_[axis] = std::max(1, static_cast<int>(per_axis));
    cells *= double(dims_[axis]);
    lo_[axis] = box.lo[axis];
    width_[axis] = extent / dims_[axis];
    inverse_width_[axis] = dims_[axis] / extent;
  }
  if (numbering == CellNumbering::kLinear) {
    if (cells > 0x1.0p62) {  // keys and key + 1 stay far from overflow
      throw InputError("cell grid too large: " + std::to_string(dims_[0]) + "x" +
                       std::to_string(dims_[1]) + "x" + std::to_string(dims_[2]) +
                       " cells exceed 2^62 keys (D = " + number_text(min_width) +
                       " is too small for the box)");
    }
    key_count_ = cell_count();
  } else {
    const int largest = std::max({dims_[0], dims_[1], dims_[2]});
    int bits = 0;
    while ((1 << bits) < largest) ++bits;
    key_count_ = std::uint64_t{1} << (3 * bits);
  }
}

bool copy_for_random_reads(const Scene& scene) {
  const std::size_t arrays = scene.has_diameters() ? 4 : 3;
  return scene.size() * arrays * sizeof(double) >= kCopyForRandomReadsFrom;
}

bool use_hashed_index(GridIndex index, const CellGrid& grid, std::size_t particles) {
  switch (index) {
    case GridIndex::kDense:
      if (!grid.dense_fits()) {
        const auto& d = grid.dims();
        throw InputError("grid=dense: the " + std::to_string(d[0]) + "x" + std::to_string(d[1]) +
                         "x" + std::to_string(d[2]) + " grid needs " +
                         std::to_string(grid.key_count()) +
                         " keys, more than a dense table's 2^28 (use grid=hashed or grid=auto)");
      }
      return false;
    case GridIndex::kHashed:
      return true;
    case GridIndex::kAuto:
      break;
  }
  const std::uint64_t keys = grid.key_count();
  return !grid.dense_fits() ||
         (keys > kDenseKeysAlways && keys / kDenseKeysPerParticle > std::uint64_t{particles});
}

std::size_t OccupiedCells::bytes() const {
  return key.capacity() * sizeof(std::uint64_t) + begin.capacity() * sizeof(std::uint32_t) +
         table.capacity() * sizeof(Entry) + filter.capacity() * sizeof(std::uint64_t);
}

void OccupiedCells::build_table(int threads) {
  const std::uint64_t cells = size();
  int bits = 1;
  while ((std::uint64_t{1} << bits) < 2 * cells) ++bits;
  const std::size_t capacity = std::size_t{1} << bits;
  shift = 64 - bits;
  table.resize(capacity);
  const int filter_bits = std::max(bits + 2, 6);  // 8 to 16 bits per cell, at least a word
  filter_shift = 64 - filter_bits;
  const std::size_t words = (std::size_t{1} << filter_bits) / 64;
  filter.resize(words);
  const std::uint64_t mask = capacity - 1;
  Entry* const entries = table.data();
  std::uint64_t* const filter_words = filter.data();
  const std::uint64_t* const keys = key.data();
#pragma omp parallel num_threads(threads)
  {
#pragma omp for schedule(static) nowait
    for (std::size_t at = 0; at < capacity; ++at) entries[at] = {kEmpty, kNone};
#pragma omp for schedule(static)
    for (std::size_t w = 0; w < words; ++w) filter_words[w] = 0;
      // Keys are distinct, so a thread claims a free place with one compare-and-swap; where a
      // cell lands depends on the threads' timing, what find() returns does not.
#pragma omp for schedule(static)
    for (std::uint64_t c = 0; c < cells; ++c) {
      const std::uint64_t k = keys[c];
      const std::uint64_t h = k * kFibonacci;
      const std::uint64_t bit = h >> filter_shift;
      std::atomic_ref<std::uint64_t>(filter_words[bit >> 6])
          .fetch_or(std::uint64_t{1} << (bit & 63), std::memory_order_relaxed);
      for (std::uint64_t at = h >> shift;; at = (at + 1) & mask) {
        std::atomic_ref<std::uint64_t> place(entries[at].key);
        std::uint64_t expected = kEmpty;
        if (place.load(std::memory_order_relaxed) == kEmpty &&
            place.compare_exchange_strong(expected, k, std::memory_order_relaxed)) {
          entries[at].cell = static_cast<std::uint32_t>(c);
          break;
        }
      }
    }
  }
}

void CellGrid::keys_of(const double* x, const double* y, const double* z, std::size_t count,
                       std::uint64_t* keys) const {
  // Through a local copy: through `this`, each store to keys could alias the grid's members,
  // which would then be reloaded per point, and the loop would not be vectorised.
  const CellGrid grid = *this;
  for (std::size_t i = 0; i < count; ++i) {
    const auto c = grid.coords_of(x[i], y[i], z[i]);
    keys[i] = grid.wide_key(c[0], c[1], c[2]);
  }
}

std::size_t CellRegistry::index_bytes() const {
  return hashed ? occupied.bytes() : cell_begin.capacity() * sizeof(std::uint32_t);
}

void CellRegistry::release_scratch() {
  LargeVector<StagedParticle>().swap(staged_);
  LargeVector<NarrowEntry>().swap(sort_buffer_);
  LargeVector<NarrowEntry>().swap(sort_scratch_);
  LargeVector<WideEntry>().swap(wide_buffer_);
  LargeVector<WideEntry>().swap(wide_scratch_);
}

std::size_t CellRegistry::buffer_bytes() const {
  auto bytes = [](const auto& v) { return v.size() * sizeof(*v.data()); };
  return index_bytes() + bytes(slot_particle) + bytes(particle_slot) + bytes(staged_) +
         bytes(sort_buffer_) + bytes(sort_scratch_) + bytes(wide_buffer_) + bytes(wide_scratch_) +
         bytes(histograms_) + bytes(new_cells_);
}

void CellRegistry::assign(const CellGrid& grid, const Scene& scene, SortedCoordinates* sorted,
                          int threads, bool hashed_index) {
  if (!hashed_index)
    use_hashed_index(GridIndex::kDense, grid, scene.size());  // throws if too large
  hashed = hashed_index;
  const std::size_t n = scene.size();
  const auto team = static_cast<std::size_t>(std::max(1, threads));
  // Only the index in use keeps memory: a hashed grid's dense table could be gigabytes.
  if (hashed) {
    LargeVector<std::uint32_t>().swap(cell_begin);
  } else {
    occupied = {};
  }
  const double start = omp_get_wtime();
  int key_bits = 1;
  while (key_bits < 64 && (std::uint64_t{1} << key_bits) < grid.key_count()) ++key_bits;
  slot_particle.resize(n);
  // Kept between runs once made (an unsorted run after a sorted one leaves it): a sweep
  // alternates orders, and a fresh 32 bytes a particle would be faulted in again each time.
  const bool stage = sorted != nullptr && copy_for_random_reads(scene);
  if (stage) staged_.resize(n);
  StagedParticle* const staged = stage ? staged_.data() : nullptr;
  if (key_bits <= 32) {
    LargeVector<WideEntry>().swap(wide_buffer_);
    LargeVector<WideEntry>().swap(wide_scratch_);
    sort_and_index(grid, scene, team, key_bits, sort_buffer_, sort_scratch_, staged);
  } else {
    LargeVector<NarrowEntry>().swap(sort_buffer_);
    LargeVector<NarrowEntry>().swap(sort_scratch_);
    sort_and_index(grid, scene, team, key_bits, wide_buffer_, wide_scratch_, staged);
  }
  if (hashed) occupied.build_table(static_cast<int>(team));
  const double registered = omp_get_wtime();
  registration_s = registered - start;

  if (sorted) {
    // The paper's reordering: coordinates copied into slot order.
    sorted->x.resize(n);
    sorted->y.resize(n);
    sorted->z.resize(n);
    sorted->diameter.resize(scene.diameter.size());
    const bool diameters = scene.has_diameters();
    // The reads are at random: each is requested kAhead slots early, so that the misses
    // overlap instead of each waiting for the last. 64: on the paper's scene the gather from
    // the scene's arrays took 0.0186 s (16 ahead), 0.0173 (32) and 0.0157 (64), 128 and 256
    // were no faster; from the staged records 16 and 32 ran 1.2x as long as 64, 128 the same.
    constexpr std::size_t kAhead = 64;
    const std::uint32_t* const particle_of = slot_particle.data();
    double *const x = sorted->x.data(), *const y = sorted->y.data(), *const z = sorted->z.data(),
                  *const d = sorted->diameter.data();
    if (staged) {
#pragma omp parallel for schedule(static) num_threads(static_cast <int>(team))
      for (std::size_t s = 0; s < n; ++s) {
        if (s + kAhead < n) __builtin_prefetch(staged + particle_of[s + kAhead]);
        const StagedParticle& p = staged[particle_of[s]];
        x[s] = p.x;
        y[s] = p.y;
        z[s] = p.z;
        if (diameters) d[s] = p.diameter;
      }
    } else {  // a scene that the caches hold: from its arrays
      const double *const in_x = scene.x.data(), *const in_y = scene.y.data(),
                          *const in_z = scene.z.data(), *const in_d = scene.diameter.data();
#pragma omp parallel for schedule(static) num_threads(static_cast <int>(team))
      for (std::size_t s = 0; s < n; ++s) {
        if (s + kAhead < n) {
          const std::uint32_t ahead = particle_of[s + kAhead];
          __builtin_prefetch(in_x + ahead);
          __builtin_prefetch(in_y + ahead);
          __builtin_prefetch(in_z + ahead);
          if (diameters) __builtin_prefetch(in_d + ahead);
        }
        const std::uint32_t i = particle_of[s];
        x[s] = in_x[i];
        y[s] = in_y[i];
        z[s] = in_z[i];
        if (diameters) d[s] = in_d[i];
      }
    }
    particle_slot.clear();
  } else {
    particle_slot.resize(n);
#pragma omp parallel for schedule(static) num_threads(static_cast <int>(team))
    for (std::size_t s = 0; s < n; ++s)
      particle_slot[slot_particle[s]] = static_cast<std::uint32_t>(s);
  }
  reorder_s = omp_get_wtime() - registered;
}

namespace {

// One particle's record, written past the caches where the target has such stores: the records
// are read back at random after the sort, by then evicted on a large scene, and a store that
// first reads its line cost the keys' pass 5 ms on the paper's scene at one thread.
inline void stage(void* record, double x, double y, double z, double diameter) {
  auto* const to = static_cast<double*>(record);
#if defined(__SSE2__)
  _mm_stream_pd(to, _mm_set_pd(y, x));
  _mm_stream_pd(to + 2, _mm_set_pd(diameter, z));
#else
  to[0] = x;
  to[1] = y;
  to[2] = z;
  to[3] = diameter;
#endif
}

// The streamed records are ordered before the barrier that lets other threads read them.
inline void staged_written() {
#if defined(__SSE2__)
  _mm_sfence();
#endif
}

// 8-bit digits: three passes over a 199^3 grid's 23-bit keys ran 6 % faster than two passes
// of 12 bits, whose 4096 scatter streams (one line each) outgrow L1 and the TLB.
constexpr int kDigitBits = 8;
constexpr std::size_t kBuckets = std::size_t{1} << kDigitBits;

constexpr std::size_t digit_of(std::uint64_t key, int shift, std::uint64_t mask = kBuckets - 1) {
  return (key >> shift) & mask;
}

// The top digit's width with `team` threads sorting: each thread then sorts whole top buckets on
// its own, so a bucket must be small beside a thread's share. The paper scene's fullest 8-bit
// top bucket holds 2.5 % of the particles, 40 % of a share at 16 threads; 6 bits more than
// log2(team) keep the fullest near a tenth of a share (up to 12 bits: 4096 buckets, whose
// scatter streams the one top pass can still afford).
int top_digit_bits(std::size_t team, int key_bits) {
  int bits = kDigitBits;
  while (bits < 12 && (std::size_t{1} << (bits - 6)) < team) ++bits;
  return std::min(bits, key_bits);
}

// One stable pass: the entries [first, last) of `source` to `target` by their digit at `shift`,
// each to the next free place of its digit in `next`, which advances.
template <class Entry>
void scatter_by_digit(const Entry* source, Entry* target, std::uint64_t first, std::uint64_t last,
                      int shift, std::uint64_t mask, std::uint64_t* next) {
  for (std::uint64_t i = first; i < last; ++i)
    target[next[digit_of(source[i].key(), shift, mask)]++] = source[i];
}

}  // namespace

// Sorts (key, input index) entries by key with a stable radix sort (lowest digit first at one
// thread, top digit first with more: see below), fills slot_particle and the cell index. A counting
// sort over the cell table would touch the (up to 2^28-entry) table at random once per particle;
// the radix passes keep their 2^kDigitBits counters in L1 and write in sequential streams. In
// parallel: each thread counts its contiguous range of the input, the ranges' offsets are laid out
// bucket by bucket in thread order (so the sort stays stable and the result is the same for any
// thread count), and each thread scatters its range.
template <class Entry>
void CellRegistry::sort_and_index(const CellGrid& grid, const Scene& scene, std::size_t team,
                                  int key_bits, LargeVector<Entry>& buffer,
                                  LargeVector<Entry>& scratch, StagedParticle* staged) {
  const std::size_t n = scene.size();
  const std::uint64_t keys = grid.key_count();
  const int passes = (key_bits + kDigitBits - 1) / kDigitBits;

  buffer.resize(n);
  scratch.resize(n);
  if (!hashed) cell_begin.resize(keys + 1);
  new_cells_.assign(team + 1, 0);
  range_totals_.resize(team);
  // The top digit goes first, over all entries, and each thread then sorts whole top buckets by
  // the lower digits on its own: every lower pass reads and writes only lines of its thread,
  // a bucket's worth, in L2. By lowest digit first, every pass scattered each thread's entries
  // into lines the other threads read in the next pass: on the paper scene (AMD EPYC VM) the
  // three passes took 5.6 ms at one thread and 5.2 ms at two, top first 3.2 ms at two. At one
  // thread that VM ran top first 0.5 ms slower (6.1 ms); the Intel Xeon VM, whose memory is
  // slower beside its L2, 4 ms faster (14.1 -> 10.1 ms, 2026-12-07), so top first at any count.
  // The top digit is the key's top kDigitBits bits (it may share bits with the last lower
  // digit, which are then the same within a top bucket): 256 buckets, so that a thread's share
  // of whole buckets is close to an even one (the paper scene's fullest holds 2.5 %; with the
  // 7 bits left above the lower digits' 16, 5 %).
  const bool top_first = passes > 1;
  const int first_bits = top_first ? top_digit_bits(team, key_bits) : kDigitBits;
  const int first_shift = top_first ? key_bits - first_bits : 0;
  const std::size_t buckets = std::size_t{1} << first_bits;  // of the first pass
  const std::uint64_t first_mask = buckets - 1;
  // Each thread zeroes its own counts (resize zeroes only entries it adds, on the first run).
  histograms_.resize(team * buckets);
  bucket_begin_.resize(buckets + 1);  // the first pass's buckets' first entries
  std::uint64_t* const bucket_begin = bucket_begin_.data();
  std::uint32_t largest = 0;
  Entry* from = buffer.data();
  Entry* to = scratch.data();
  std::uint64_t squares = 0;
#pragma omp parallel num_threads(static_cast <int>(team)) reduction(max : largest) \
    reduction(+ : squares)
  {
    const auto t = static_cast<std::size_t>(omp_get_thread_num());
    const std::size_t size = static_cast<std::size_t>(omp_get_num_threads());
    std::size_t b = n * t / size, e = n * (t + 1) / size;
    std::uint64_t* mine = histograms_.data() + t * buckets;
    std::fill(mine, mine + buckets, 0);
    // The keys, a block at a time on SIMD lanes, and with them the first pass's histogram. A
    // dense grid's wide keys are its keys.
    constexpr std::size_t kKeyBlock = 256;
    std::uint64_t block_keys[kKeyBlock];
    const double* const diameter = scene.diameter.empty() ? nullptr : scene.diameter.data();
    for (std::size_t first = b; first < e; first += kKeyBlock) {
      const std::size_t count = std::min(kKeyBlock, e - first);
      grid.keys_of(scene.x.data() + first, scene.y.data() + first, scene.z.data() + first, count,
                   block_keys);
      for (std::size_t k = 0; k < count; ++k) {
        from[first + k] = Entry::make(block_keys[k], first + k);
        ++mine[digit_of(block_keys[k], first_shift, first_mask)];
      }
      if (staged) {
        for (std::size_t i = first; i < first + count; ++i) {
          stage(staged + i, scene.x[i], scene.y[i], scene.z[i], diameter ? diameter[i] : 0.0);
        }
      }
    }
    if (staged) staged_written();
    Entry* in = from;
    Entry* out = to;
    // One stable pass over [b, e) by the digit at `shift`, from `in` to `out`, with this thread's
    // histogram (the first pass's counted with the keys) laid out by the other threads'.
    auto shared_pass = [&](int shift, bool counted) {
      if (!counted) {
        const Entry* const source = in;
        std::uint64_t* const counts = mine;
        std::fill(counts, counts + buckets, 0);
        for (std::size_t i = b; i < e; ++i) ++counts[digit_of(source[i].key(), shift, first_mask)];
      }
      // Offsets: bucket by bucket, within a bucket thread by thread. Each thread lays out an
      // equal range of the buckets, after the ranges before it (one thread laying out all
      // buckets x threads counts took 0.3 ms at 64 threads).
      const std::size_t bucket_first = buckets * t / size, bucket_last = buckets * (t + 1) / size;
      std::uint64_t range_total = 0;
#pragma omp barrier
      for (std::size_t bucket = bucket_first; bucket < bucket_last; ++bucket) {
        for (std::size_t u = 0; u < size; ++u) range_total += histograms_[u * buckets + bucket];
      }
      range_totals_[t] = range_total;
#pragma omp barrier
      std::uint64_t running = 0;
      for (std::size_t u = 0; u < t; ++u) running += range_totals_[u];
      for (std::size_t bucket = bucket_first; bucket < bucket_last; ++bucket) {
        bucket_begin[bucket] = running;
        for (std::size_t u = 0; u < size; ++u) {
          running += std::exchange(histograms_[u * buckets + bucket], running);
        }
      }
      if (t + 1 == size) bucket_begin[buckets] = running;
#pragma omp barrier
      scatter_by_digit(in, out, b, e, shift, first_mask, mine);
      std::swap(in, out);
#pragma omp barrier
    };
    if (!top_first) {
      for (int pass = 0; pass < passes; ++pass) shared_pass(pass * kDigitBits, pass == 0);
    } else {
      shared_pass(first_shift, true);
      // This thread's top buckets: those starting in its share of the entries. Its slots are
      // theirs from here on (the cell index below included).
      const auto* const starts = bucket_begin;
      b = *std::lower_bound(starts, starts + buckets + 1, n * t / size);
      e = *std::lower_bound(starts, starts + buckets + 1, n * (t + 1) / size);
      // The lower digits' histograms of a bucket in one read of it (at most 7 lower digits).
      std::array<std::uint64_t, 7 * kBuckets> counts;
      for (std::size_t bucket = 0; bucket < buckets; ++bucket) {
        const std::uint64_t first = bucket_begin[bucket], last = bucket_begin[bucket + 1];
        if (first < b || first >= e || last == first) continue;
        std::fill(counts.begin(), counts.begin() + (passes - 1) * kBuckets, 0);
        for (std::uint64_t i = first; i < last; ++i) {
          const std::uint64_t key = in[i].key();
          for (int pass = 0; pass + 1 < passes; ++pass)
            ++counts[pass * kBuckets + digit_of(key, pass * kDigitBits)];
        }
        Entry* bucket_in = in;
        Entry* bucket_out = out;
        for (int pass = 0; pass + 1 < passes; ++pass) {
          std::uint64_t* const next = counts.data() + pass * kBuckets;
          std::uint64_t running = first;
          for (std::size_t digit = 0; digit < kBuckets; ++digit)
            running += std::exchange(next[digit], running);
          scatter_by_digit(bucket_in, bucket_out, first, last, pass * kDigitBits, kBuckets - 1,
                           next);
          std::swap(bucket_in, bucket_out);
        }
      }
      // Every bucket made the same number of passes: the sorted entries are where the lowest
      // digit first leaves them.
      if ((passes - 1) % 2 == 1) std::swap(in, out);
#pragma omp barrier
    }
    // Slots in key order. A cell starts at slot s when s == 0 or slot s - 1 has another key.
    auto starts_cell = [&](std::size_t s) { return s == 0 || in[s - 1].key() != in[s].key(); };
    // One pass without branches on the data (in a clustered scene whether a slot starts a cell
    // is a coin toss). The occupancies' sum of squares and maximum by each slot's rank r in its
    // cell: a cell of m slots adds 2r + 1 over r < m, which is m^2, and its last slot r + 1 = m,
    // wherever the threads' ranges cut it.
    if (b < e) {
      std::size_t cell_start = b;  // of the cell holding slot b: it may begin in an earlier range
      while (cell_start > 0 && in[cell_start - 1].key() == in[b].key()) --cell_start;
      std::uint64_t previous = b == 0 ? ~std::uint64_t{0} : in[b - 1].key();  // ~0: none
      // cell_begin[k] = the first slot whose key is >= k: the cell starting at slot s sets it
      // for the keys after the previous slot's up to its own. Each thread sets those its slots
      // start, up to its last slot's key (the next range sets the ones after): disjoint. Every
      // slot stores kFill entries from the key after the previous slot's, one vector store,
      // without asking whether it starts a cell or how far the gap reaches: entries past the
      // gap are set again by the slots after it, and only a gap longer than kFill or the range's
      // last keys take the exact loop.
      constexpr std::uint64_t kFill = 16;
      const std::uint64_t last_key = in[e - 1].key();
      std::uint32_t* const begin_of = hashed ? nullptr : cell_begin.data();
      // Locals, not the reduction's variables: GCC kept the maximum on the stack, a store and a
      // reload per slot.
      const Entry* const sorted = in;
      std::uint32_t* const particle_of = slot_particle.data();
      std::uint64_t squares_here = 0, largest_rank = 0;
      for (std::size_t s = b; s < e; ++s) {
        const std::uint64_t key = sorted[s].key();
        particle_of[s] = sorted[s].index();
        // All ones where slot s starts a cell. Hidden from the optimiser, which otherwise
        // branched on it to skip the rank's arithmetic for a cell's first slot, a coin toss in
        // a clustered scene (this pass: 5.6 ms with the branch, 3.9 ms without, paper scene).
        std::uint64_t starts = -static_cast<std::uint64_t>(key != previous);
        asm("" : "+r"(starts));
        cell_start = (s & starts) | (cell_start & ~starts);
        const std::uint64_t rank = s - cell_start;
        squares_here += 2 * rank + 1;
        largest_rank = std::max(largest_rank, rank);
        if (begin_of) {
          const auto slot = static_cast<std::uint32_t>(s);
          const std::uint64_t k = previous + 1;
          if (k + kFill - 1 <= last_key) [[likely]] {
            for (std::uint64_t j = 0; j < kFill; ++j) begin_of[k + j] = slot;
            // A gap past kFill keys (7 % of the paper scene's slots).
            if (key >= k + kFill) [[unlikely]] {
              for (std::uint64_t gap = k + kFill; gap <= key; ++gap) begin_of[gap] = slot;
            }
          } else {
            for (std::uint64_t gap = k; gap <= key; ++gap) begin_of[gap] = slot;
          }
        }
        previous = key;
      }
      squares += squares_here;
      largest = std::max(largest, static_cast<std::uint32_t>(largest_rank + 1));
    }
    if (!hashed) {  // the keys past the last particle's (all when there is none), shared out
      const std::uint64_t after = n == 0 ? 0 : in[n - 1].key() + 1;
      std::uint32_t* const begin_of = cell_begin.data();
#pragma omp for schedule(static) nowait
      for (std::uint64_t k = after; k <= keys; ++k) begin_of[k] = static_cast<std::uint32_t>(n);
    }
    if (hashed) {
      // The occupied cells, listed by each thread for its slots at its place in the list.
      std::uint64_t cells_here = 0;
      for (std::size_t s = b; s < e; ++s) cells_here += starts_cell(s);
      new_cells_[t + 1] = cells_here;
#pragma omp barrier
#pragma omp single
      {
        for (std::size_t u = 0; u < size; ++u) new_cells_[u + 1] += new_cells_[u];
        occupied.key.resize(new_cells_[size]);
        occupied.begin.resize(new_cells_[size] + 1);
        occupied.begin[new_cells_[size]] = static_cast<std::uint32_t>(n);
      }  // implicit barrier
      std::uint64_t c = new_cells_[t];
      for (std::size_t s = b; s < e; ++s) {
        if (!starts_cell(s)) continue;
        occupied.key[c] = in[s].key();
        occupied.begin[c] = static_cast<std::uint32_t>(s);
        ++c;
      }
    }
  }
  if (passes % 2 == 1) buffer.swap(scratch);  // the sorted entries' vector first
  max_occupancy = largest;
  occupancy_squares = squares;
}

}  // namespace contactlab
