// std::vector for the large arrays of the kernels (cell tables, particle arrays), backed by
// transparent huge pages where the system offers them: the cell table of a 200^3 grid is
// 32 MB, read at random, and with 4 KiB pages nearly every access also misses the TLB. Its
// resize() leaves new elements uninitialised: a LargeVector is written before it is read.
#pragma once

#include <sys/mman.h>

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <new>
#include <utility>
#include <vector>

namespace contactlab {

// Huge allocations start at a rotating offset ("colour") past a huge-page boundary. Arrays read
// side by side (the sorted x, y, z and diameters) that all began on a 2 MiB boundary would put
// x[i], y[i] and z[i] in one set of every cache whose way is a divisor of 2 MiB: a 2-way L1
// such as the FX10's (16 KiB a way) then holds two of the three, and the scalar pair loop
// missed on every coordinate it read (simulated FX10, N = 300,000: 3.05 L1 misses per candidate
// test instead of 0.125, docs/measurement.md). Consecutive allocations get colours 0..3, 4 KiB
// apart: distinct sets of a 16 KiB way. The step is whole 4 KiB pages because offsets within a
// page cost x86 cores with 4 KiB ways and many of them (a 48 KiB 12-way L1) about 3 % of the
// paper scene's pair loop (17 lines apart, interleaved against no offsets, 1 and 2 threads).
inline constexpr std::size_t kCacheLine = 64;  // bytes

namespace large_vector_detail {
inline constexpr std::size_t kHugePage = std::size_t{2} << 20;
inline constexpr std::size_t kColourStep = std::size_t{4096};  // bytes
inline constexpr std::size_t kColours = 4;

inline std::size_t next_colour_offset() {
  static std::atomic<std::size_t> next{0};
  return next.fetch_add(1, std::memory_order_relaxed) % kColours * kColourStep;
}
}  // namespace large_vector_detail

template <class T>
struct HugePageAllocator {
  using value_type = T;
  static constexpr std::size_t kHugePage = large_vector_detail::kHugePage;

  HugePageAllocator() = default;
  template <class U>
  HugePageAllocator(const HugePageAllocator<U>&) noexcept {}

  T* allocate(std::size_t n) {
    static_assert(alignof(T) <= kCacheLine, "colours and small blocks keep a cache line only");
    const std::size_t bytes = n * sizeof(T);
    if (bytes < kHugePage) {  // on a cache line, as the colours keep it
      const std::size_t lines = bytes == 0 ? 1 : (bytes + kCacheLine - 1) / kCacheLine;
      if (void* p = std::aligned_alloc(kCacheLine, lines * kCacheLine)) return static_cast<T*>(p);
      throw std::bad_alloc();
    }
    const std::size_t offset = large_vector_detail::next_colour_offset();
    const std::size_t rounded = (offset + bytes + kHugePage - 1) / kHugePage * kHugePage;
    void* p = std::aligned_alloc(kHugePage, rounded);
    if (!p) throw std::bad_alloc();
    ::madvise(p, rounded, MADV_HUGEPAGE);  // advice only: failure leaves ordinary pages
    return reinterpret_cast<T*>(static_cast<char*>(p) + offset);
  }
  // The block began at the huge-page boundary below p (offsets are less than a huge page);
  // allocations under a huge page came from aligned_alloc unchanged.
  void deallocate(T* p, std::size_t n) noexcept {
    if (n * sizeof(T) < kHugePage) {
      std::free(p);
      return;
    }
    const auto offset = reinterpret_cast<std::uintptr_t>(p) & std::uintptr_t{kHugePage - 1};
    std::free(reinterpret_cast<char*>(p) - offset);
  }
  // resize() default-initialises (no zeroing of trivial types): every user writes all of a
  // buffer before it reads it, and the first write, in the parallel loops, places the pages
  // with the thread that uses them (first touch) instead of one thread's memset.
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    if constexpr (sizeof...(Args) == 0) {
      ::new (static_cast<void*>(p)) U;
    } else {
      ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
    }
  }

  template <class U>
  bool operator==(const HugePageAllocator<U>&) const noexcept {
    return true;
  }
};

template <class T>
using LargeVector = std::vector<T, HugePageAllocator<T>>;

}  // namespace contactlab
