// std::vector whose storage starts on a cache line (64 bytes), for arrays read and written with
// vector loads and stores of a whole line (the DEM's per-particle and per-pair arrays, eight
// doubles a lane group). std::allocator gives 16 bytes: glibc hands a large block out 16 bytes
// past a page, so every 64-byte access at an index that is a multiple of eight straddles two
// lines. On the settled 65,536-sphere bed, aligned, the step ran 1.14x as fast with AVX-512 and
// 1.10x with AVX2 (docs/dem.md). Elements are value-initialised as in std::vector (unlike
// LargeVector).
#pragma once

#include <cstddef>
#include <new>
#include <vector>

namespace contactlab {

inline constexpr std::size_t kCacheLine = 64;

template <class T>
struct CacheLineAllocator {
  using value_type = T;
  static_assert(alignof(T) <= kCacheLine);

  CacheLineAllocator() = default;
  template <class U>
  CacheLineAllocator(const CacheLineAllocator<U>&) noexcept {}

  T* allocate(std::size_t n) {
    return static_cast<T*>(::operator new (n * sizeof(T), std::align_val_t{kCacheLine}));
  }
  void deallocate(T* p, std::size_t /*n*/) noexcept {
    ::operator delete (p, std::align_val_t{kCacheLine});
  }
  template <class U>
  bool operator==(const CacheLineAllocator<U>&) const noexcept {
    return true;
  }
};

template <class T>
using AlignedVector = std::vector<T, CacheLineAllocator<T>>;

}  // namespace contactlab
