// Eight particles' kinematics blocks as columns (the x of all eight, their y, ...), by two
// 64-byte loads per block and in-register transposes (private to src/). The pair kernel uses
// it to fill eight lanes of a field at once: eleven scalar loads per field and pair cost more
// than the pair law itself.
// Compiled once per instruction set (dem_isa.hpp): a toggle, no include guard.

#include <cmath>
#include <cstdint>
#include <cstring>

#include "dem_isa.hpp"
#include "lanes.hpp"

#if defined(CONTACTLAB_DEM_KIN_COLUMNS_TOGGLE) == defined(CONTACTLAB_DEM_ISA_TOGGLE)
#ifdef CONTACTLAB_DEM_KIN_COLUMNS_TOGGLE
#undef CONTACTLAB_DEM_KIN_COLUMNS_TOGGLE
#else
#define CONTACTLAB_DEM_KIN_COLUMNS_TOGGLE
#endif

namespace contactlab::dem::detail {
CONTACTLAB_DEM_ISA_NAMESPACE(build) {

// The kinematics of eight particles, a field per vector (the kin block's layout: x, y, z, r,
// pvx, pvy, pvz, m, pwx, pwy, pwz, unused).
struct KinColumns {
  Lanes x, y, z, r, vx, vy, vz, m, wx, wy, wz;
};

// Doubles 8 .. 10 (the spins) of the blocks of particles index[0..7] as columns.
template <class P = LanePart>
[[gnu::always_inline]] inline void spin_columns(const double* kin, std::size_t stride,
                                                const std::uint32_t* index, Lanes& wx, Lanes& wy,
                                                Lanes& wz) {
  Lanes unused;
  if constexpr (sizeof(P) == 64) {
    // The spins of blocks p and p + 4 in one register from two 32-byte loads: the third 32
    // bytes of a 96-byte block never straddle two lines of a line-aligned array, where a
    // 64-byte load from double 4 did in every other block.
    using Quarter = double __attribute__((vector_size(4 * sizeof(double))));
    P quarters[4];
    for (std::size_t p = 0; p < 4; ++p) {
      Quarter lo, hi;
      std::memcpy(&lo, kin + stride * index[p] + 8, sizeof lo);
      std::memcpy(&hi, kin + stride * index[p + 4] + 8, sizeof hi);
      quarters[p] = __builtin_shufflevector(lo, hi, 0, 1, 2, 3, 4, 5, 6, 7);
    }
    columns_of_paired_quarters(quarters, wx, wy, wz, unused);
  } else {
    Lanes tail[8];  // pvx .. unused; only the spins are used, and only their registers loaded
    for (std::size_t l = 0; l < kLanes; ++l) tail[l] = load_lanes(kin + stride * index[l] + 4);
    top_columns(tail, wx, wy, wz, unused);
  }
}

// The blocks of particles index[0..7], `stride` doubles apart from kin.
[[gnu::always_inline]] inline KinColumns kin_columns(const double* kin, std::size_t stride,
                                                     const std::uint32_t* index) {
  Lanes head[8], c[8];
  for (std::size_t l = 0; l < kLanes; ++l) head[l] = load_lanes(kin + stride * index[l]);  // x .. m
  transpose8(head, c);
  KinColumns k{c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7], {}, {}, {}};
  spin_columns(kin, stride, index, k.wx, k.wy, k.wz);
  return k;
}

}  // CONTACTLAB_DEM_ISA_NAMESPACE(build)
}  // namespace contactlab::dem::detail

#endif
