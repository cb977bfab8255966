// LargeVector: huge allocations start at staggered offsets past their 2 MiB boundary, so that
// arrays read side by side do not share the sets of a low-associativity cache (the simulated
// FX10 L1: 2 ways of 16 KiB), and they are freed from the block's start. Smaller ones, and
// every AlignedVector, start on a cache line (a vector load of eight doubles at an index that
// is a multiple of eight is then one line, not two).
#include <gtest/gtest.h>

#include <cstdint>
#include <set>

#include "contactlab/kernels/aligned_vector.hpp"
#include "contactlab/kernels/large_vector.hpp"

namespace contactlab {
namespace {

std::uintptr_t address(const void* p) { return reinterpret_cast<std::uintptr_t>(p); }

// x, y and z of 300,000 particles (2.4 MB each), allocated one after another as the sorted
// coordinates are: distinct positions within a 16 KiB way, 64-byte aligned, and whole pages apart
// (where a 4 KiB way has many ways, the same place in it costs nothing and other places did).
TEST(LargeVector, ArraysAllocatedInTurnFallInDifferentSets) {
  constexpr std::size_t kN = 300000;
  static_assert(kN * sizeof(double) >= HugePageAllocator<double>::kHugePage);
  LargeVector<double> x(kN), y(kN), z(kN);
  std::set<std::uintptr_t> in_16k, in_4k;
  for (const auto* v : {&x, &y, &z}) {
    EXPECT_EQ(address(v->data()) % 64, 0u);
    in_16k.insert(address(v->data()) % 16384 / 128);  // the set of a 2-way 32 KiB, 128 B L1
    in_4k.insert(address(v->data()) % 4096);          // of a 48 KiB 12-way, 64 B L1
  }
  EXPECT_EQ(in_16k.size(), 3u);
  EXPECT_EQ(in_4k.size(), 1u);
  // Every element is usable (the offset is inside the block, the block large enough).
  for (std::size_t i = 0; i < kN; ++i) x[i] = y[i] = z[i] = static_cast<double>(i);
  constexpr std::size_t kMiddle = kN / 2;
  EXPECT_EQ(x[kN - 1] + y[0] + z[kMiddle], static_cast<double>(kN - 1 + kMiddle));
}

// Growing, shrinking and swapping free every block from its start: under the sanitizer
// presets a wrong pointer to free() is reported.
TEST(LargeVector, GrowsShrinksAndSwapsAcrossTheHugeThreshold) {
  LargeVector<std::uint32_t> a(10), b(1000000);
  a.resize(2000000);
  for (std::size_t i = 0; i < a.size(); ++i) a[i] = static_cast<std::uint32_t>(i);
  a.swap(b);
  EXPECT_EQ(a.size(), 1000000u);
  EXPECT_EQ(b[1999999], 1999999u);
  b.resize(5);
  b.shrink_to_fit();
  EXPECT_EQ(b[4], 4u);
  LargeVector<std::uint32_t>().swap(a);
  EXPECT_TRUE(a.empty());
}

// Sizes on both sides of glibc's mmap threshold (128 KiB by default), where malloc's blocks
// begin 16 bytes past a page: each starts on a cache line, and stays so as it grows.
TEST(LargeVector, SmallArraysStartOnACacheLine) {
  for (const std::size_t n : {std::size_t{1}, std::size_t{7}, std::size_t{1000}, std::size_t{65536},
                              std::size_t{200000}}) {
    const LargeVector<double> v(n);
    EXPECT_EQ(address(v.data()) % kCacheLine, 0u) << n;
  }
  LargeVector<double> empty;
  empty.reserve(0);
  empty.push_back(1.0);
  EXPECT_EQ(address(empty.data()) % kCacheLine, 0u);
}

TEST(AlignedVector, StartsOnACacheLineAndValueInitialises) {
  for (const std::size_t n : {std::size_t{1}, std::size_t{9}, std::size_t{4096}, std::size_t{65536},
                              std::size_t{300000}}) {
    AlignedVector<double> v(n);
    EXPECT_EQ(address(v.data()) % kCacheLine, 0u) << n;
    EXPECT_EQ(v.front(), 0.0);
    EXPECT_EQ(v.back(), 0.0);
    v.resize(3 * n, 2.0);  // regrown: a new block, again on a line
    EXPECT_EQ(address(v.data()) % kCacheLine, 0u) << n;
    EXPECT_EQ(v[n - 1], 0.0);
    EXPECT_EQ(v[3 * n - 1], 2.0);
  }
  AlignedVector<std::uint16_t> small(3), other(70000, 5);
  small.swap(other);
  EXPECT_EQ(address(small.data()) % kCacheLine, 0u);
  EXPECT_EQ(small[69999], 5u);
}

}  // namespace
}  // namespace contactlab
