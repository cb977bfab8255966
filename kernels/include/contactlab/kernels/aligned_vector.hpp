// std::vector on LargeVector's storage (a cache line at least, transparent huge pages from
// 2 MiB) with std::vector's value-initialisation, for the arrays read and written with vector
// loads and stores of a whole line (the DEM's per-particle and per-pair arrays, eight doubles a
// lane group). std::allocator gives 16 bytes: glibc hands a large block out 16 bytes past a
// page, so every 64-byte access at an index that is a multiple of eight straddled two lines.
// On the settled 65,536-sphere bed, aligned, the step ran 1.14x as fast with AVX-512 and 1.10x
// with AVX2; huge pages for its large arrays (the kinematics blocks, the sums, the springs and
// pair constants) added 1.06x (docs/dem.md).
#pragma once

#include <cstddef>
#include <new>
#include <utility>
#include <vector>

#include "contactlab/kernels/large_vector.hpp"

namespace contactlab {

template <class T>
struct CacheLineAllocator : HugePageAllocator<T> {
  CacheLineAllocator() = default;
  template <class U>
  CacheLineAllocator(const CacheLineAllocator<U>&) noexcept {}

  // Value-initialises as std::allocator does (resize() zeroes new doubles); HugePageAllocator
  // leaves them as they are.
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
  template <class U>
  bool operator==(const CacheLineAllocator<U>&) const noexcept {
    return true;
  }
};

template <class T>
using AlignedVector = std::vector<T, CacheLineAllocator<T>>;

}  // namespace contactlab
