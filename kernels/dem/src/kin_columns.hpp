// Eight particles' kinematics blocks as columns (the x of all eight, their y, ...), by two
// vector loads per block and in-register 8x8 transposes (private to src/). The pair kernel
// uses it to fill eight lanes of a field at once: eleven scalar loads per field and pair cost
// more than the pair law itself. GCC vector extensions: AVX-512 shuffles
// where -march allows, narrower vectors elsewhere, the same values on every target. Clang
// (clang-tidy) compiles it too: see CONTACTLAB_SHUFFLE.
// Compiled once per instruction set (dem_isa.hpp): a toggle, no include guard.

#include <cmath>
#include <cstdint>
#include <cstring>

#include "dem_isa.hpp"

#if defined(CONTACTLAB_DEM_KIN_COLUMNS_TOGGLE) == defined(CONTACTLAB_DEM_ISA_TOGGLE)
#ifdef CONTACTLAB_DEM_KIN_COLUMNS_TOGGLE
#undef CONTACTLAB_DEM_KIN_COLUMNS_TOGGLE
#else
#define CONTACTLAB_DEM_KIN_COLUMNS_TOGGLE
#endif

namespace contactlab::dem::detail {
CONTACTLAB_DEM_ISA_NAMESPACE(build) {

using Lanes = double __attribute__((vector_size(64)));
using LaneIndex = std::int64_t __attribute__((vector_size(64)));
constexpr std::size_t kLanes = 8;

inline Lanes load_lanes(const double* p) {
  Lanes v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
inline void store_lanes(double* p, const Lanes& v) { std::memcpy(p, &v, sizeof v); }

// GCC's __builtin_shuffle(a, [b,] mask): lanes 0..7 of a, 8..15 of b. Clang has no such builtin
// (its __builtin_shufflevector takes the lane indices as constant arguments, not as a vector):
// there, lane by lane, which clang folds into the same single shuffles once the constant mask
// is inlined. Under GCC the code is the builtin itself, as before.
#if defined(__clang__)
template <class V>
[[gnu::always_inline]] inline V shuffle_lanes(const V& a, const V& b, const LaneIndex& mask) {
  constexpr std::int64_t kWidth = kLanes;
  V r;
  for (std::int64_t l = 0; l < kWidth; ++l) {
    const std::int64_t from = mask[l];
    r[l] = from < kWidth ? a[from] : b[from - kWidth];
  }
  return r;
}
template <class V>
[[gnu::always_inline]] inline V shuffle_lanes(const V& a, const LaneIndex& mask) {
  return shuffle_lanes(a, a, mask);
}
#define CONTACTLAB_SHUFFLE shuffle_lanes
#else
#define CONTACTLAB_SHUFFLE __builtin_shuffle
#endif

// Whether any lane of a comparison's mask is set, or false.
[[gnu::always_inline]] inline bool any_set(const LaneIndex& mask) {
  LaneIndex m = mask;
  m |= CONTACTLAB_SHUFFLE(m, LaneIndex{4, 5, 6, 7, 0, 1, 2, 3});
  m |= CONTACTLAB_SHUFFLE(m, LaneIndex{2, 3, 0, 1, 6, 7, 4, 5});
  m |= CONTACTLAB_SHUFFLE(m, LaneIndex{1, 0, 3, 2, 5, 4, 7, 6});
  return m[0] != 0;
}
[[gnu::always_inline]] inline bool any_false(const LaneIndex& m) { return any_set(~m); }

// Rows r[0..7] of eight doubles in, their columns out (c[k][l] = r[l][k]).
[[gnu::always_inline]] inline void transpose8(const Lanes (&r)[8], Lanes (&c)[8]) {
  constexpr LaneIndex kEven{0, 8, 2, 10, 4, 12, 6, 14}, kOdd{1, 9, 3, 11, 5, 13, 7, 15};
  constexpr LaneIndex kPairLo{0, 1, 8, 9, 4, 5, 12, 13}, kPairHi{2, 3, 10, 11, 6, 7, 14, 15};
  constexpr LaneIndex kHalfLo{0, 1, 2, 3, 8, 9, 10, 11}, kHalfHi{4, 5, 6, 7, 12, 13, 14, 15};
  Lanes t[8], u[8];
  for (int p = 0; p < 8; p += 2) {
    t[p] = CONTACTLAB_SHUFFLE(r[p], r[p + 1], kEven);  // columns 0, 2, 4, 6 of rows p, p + 1
    t[p + 1] = CONTACTLAB_SHUFFLE(r[p], r[p + 1], kOdd);
  }
  for (int h = 0; h < 8; h += 4) {  // rows h .. h + 3: columns (0, 4), (1, 5), (2, 6), (3, 7)
    u[h] = CONTACTLAB_SHUFFLE(t[h], t[h + 2], kPairLo);
    u[h + 1] = CONTACTLAB_SHUFFLE(t[h + 1], t[h + 3], kPairLo);
    u[h + 2] = CONTACTLAB_SHUFFLE(t[h], t[h + 2], kPairHi);
    u[h + 3] = CONTACTLAB_SHUFFLE(t[h + 1], t[h + 3], kPairHi);
  }
  for (int k = 0; k < 4; ++k) {
    c[k] = CONTACTLAB_SHUFFLE(u[k], u[k + 4], kHalfLo);
    c[k + 4] = CONTACTLAB_SHUFFLE(u[k], u[k + 4], kHalfHi);
  }
}

// The kinematics of eight particles, a field per vector (the kin block's layout: x, y, z, r,
// pvx, pvy, pvz, m, pwx, pwy, pwz, unused).
struct KinColumns {
  Lanes x, y, z, r, vx, vy, vz, m, wx, wy, wz;
};

// Columns 0..3 of the top halves of rows r[0..7] (lanes 4..7 of each): 12 shuffles, not a
// full transpose's 24 for half of its columns.
[[gnu::always_inline]] inline void top_columns(const Lanes (&r)[8], Lanes& c0, Lanes& c1, Lanes& c2,
                                               Lanes& c3) {
  constexpr LaneIndex kTops{4, 5, 6, 7, 12, 13, 14, 15};
  constexpr LaneIndex kEven{0, 8, 2, 10, 4, 12, 6, 14}, kOdd{1, 9, 3, 11, 5, 13, 7, 15};
  constexpr LaneIndex kPairLo{0, 1, 8, 9, 4, 5, 12, 13}, kPairHi{2, 3, 10, 11, 6, 7, 14, 15};
  Lanes q[4];  // the tops of rows p and p + 4, side by side
  for (int p = 0; p < 4; ++p) q[p] = CONTACTLAB_SHUFFLE(r[p], r[p + 4], kTops);
  // even01: c0 of 0 1, c2 of 0 1, c0 of 4 5, ..; odd01: c1 of 0 1, c3 of 0 1, ..
  const Lanes even01 = CONTACTLAB_SHUFFLE(q[0], q[1], kEven);
  const Lanes odd01 = CONTACTLAB_SHUFFLE(q[0], q[1], kOdd);
  const Lanes even23 = CONTACTLAB_SHUFFLE(q[2], q[3], kEven);
  const Lanes odd23 = CONTACTLAB_SHUFFLE(q[2], q[3], kOdd);
  c0 = CONTACTLAB_SHUFFLE(even01, even23, kPairLo);
  c2 = CONTACTLAB_SHUFFLE(even01, even23, kPairHi);
  c1 = CONTACTLAB_SHUFFLE(odd01, odd23, kPairLo);
  c3 = CONTACTLAB_SHUFFLE(odd01, odd23, kPairHi);
}

// The square roots of eight lanes (a loop the compiler turns into one vector sqrt: GCC's
// vector extensions have no sqrt of their own; the same IEEE result as std::sqrt per lane).
[[gnu::always_inline]] inline Lanes sqrt_lanes(const Lanes& v) {
  double in[kLanes], out[kLanes];
  std::memcpy(in, &v, sizeof in);
#pragma omp simd
  for (std::size_t l = 0; l < kLanes; ++l) out[l] = std::sqrt(in[l]);
  Lanes r;
  std::memcpy(&r, out, sizeof r);
  return r;
}

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

#undef CONTACTLAB_SHUFFLE

#endif
