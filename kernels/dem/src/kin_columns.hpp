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

// The blocks of particles index[0..7], `stride` doubles apart from kin.
[[gnu::always_inline]] inline KinColumns kin_columns(const double* kin, std::size_t stride,
                                                     const std::uint32_t* index) {
  Lanes head[8], tail[8], c[8];
  for (std::size_t l = 0; l < kLanes; ++l) {
    const double* block = kin + stride * index[l];
    head[l] = load_lanes(block);      // x .. m
    tail[l] = load_lanes(block + 4);  // pvx .. unused (only the spins are kept)
  }
  transpose8(head, c);
  KinColumns k{c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7], {}, {}, {}};
  Lanes unused;
  top_columns(tail, k.wx, k.wy, k.wz, unused);
  return k;
}

}  // CONTACTLAB_DEM_ISA_NAMESPACE(build)
}  // namespace contactlab::dem::detail

#endif
