// Eight doubles on SIMD lanes, the DEM kernels' unit of work (private to src/): eight pairs
// through the contact law, eight particles through the update, an eight-double pair record.
//
// A Lanes value is held in as many registers as the instruction set needs for 64 bytes: one
// where a register holds eight doubles (AVX-512), two of four (AVX2), four of two (SSE2). A
// single 64-byte GCC vector was the first form; without AVX-512 it has no machine mode, so GCC
// kept every value in memory and lowered each shuffle lane by lane (an 8x8 transpose: 59
// instructions under AVX-512, 289 under AVX2), and the AVX2 step ran at 0.37 of the AVX-512 one
// (issue #48). As parts of the register width, every operation is a register operation on
// every set, and each lane still computes exactly the scalar law's operations (the kernels are
// bit-identical across sets: dem_step_isa_gtest).
// Compiled once per instruction set (dem_isa.hpp): a toggle, no include guard. The caller of
// a pass sets CONTACTLAB_DEM_LANE_PARTS; otherwise the build's flags decide.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#if defined(__x86_64__)
#include <immintrin.h>
#endif

#include "dem_isa.hpp"

#if defined(CONTACTLAB_DEM_LANES_TOGGLE) == defined(CONTACTLAB_DEM_ISA_TOGGLE)
#ifdef CONTACTLAB_DEM_LANES_TOGGLE
#undef CONTACTLAB_DEM_LANES_TOGGLE
#else
#define CONTACTLAB_DEM_LANES_TOGGLE
#endif

namespace contactlab::dem::detail {
CONTACTLAB_DEM_ISA_NAMESPACE(build) {

constexpr std::size_t kLanes = 8;
#if defined(CONTACTLAB_DEM_LANE_PARTS)
#define CONTACTLAB_DEM_PARTS CONTACTLAB_DEM_LANE_PARTS
#elif defined(__AVX512F__)
#define CONTACTLAB_DEM_PARTS 1
#elif defined(__AVX__)
#define CONTACTLAB_DEM_PARTS 2
#else
#define CONTACTLAB_DEM_PARTS 4
#endif
constexpr std::size_t kLaneParts = CONTACTLAB_DEM_PARTS;
static_assert(kLaneParts == 1 || kLaneParts == 2 || kLaneParts == 4);
// Lanes a register holds.
constexpr std::size_t kPartLanes = kLanes / kLaneParts;

using LanePart = double __attribute__((vector_size(sizeof(double) * kPartLanes)));
using MaskPart = std::int64_t __attribute__((vector_size(sizeof(double) * kPartLanes)));

#if CONTACTLAB_DEM_PARTS == 1
// One register: the GCC vector itself, its operators, a mask as its comparisons give it.
using Lanes = LanePart;
using LaneMask = MaskPart;
[[gnu::always_inline]] inline LanePart& part_of(Lanes& v, std::size_t /*p*/) { return v; }
[[gnu::always_inline]] inline const LanePart& part_of(const Lanes& v, std::size_t /*p*/) {
  return v;
}
[[gnu::always_inline]] inline MaskPart& part_of(LaneMask& v, std::size_t /*p*/) { return v; }
[[gnu::always_inline]] inline const MaskPart& part_of(const LaneMask& v, std::size_t /*p*/) {
  return v;
}
#else
// A comparison's result: all ones where true, zero where false.
struct LaneMask {
  MaskPart part[kLaneParts];
};

struct Lanes {
  LanePart part[kLaneParts];
  [[gnu::always_inline]] double operator[](std::size_t l) const {
    return part[l / kPartLanes][l % kPartLanes];
  }
};
[[gnu::always_inline]] inline LanePart& part_of(Lanes& v, std::size_t p) { return v.part[p]; }
[[gnu::always_inline]] inline const LanePart& part_of(const Lanes& v, std::size_t p) {
  return v.part[p];
}
[[gnu::always_inline]] inline MaskPart& part_of(LaneMask& v, std::size_t p) { return v.part[p]; }
[[gnu::always_inline]] inline const MaskPart& part_of(const LaneMask& v, std::size_t p) {
  return v.part[p];
}
#endif

// The part loops below have one to four trips: always unrolled, so every part is a register.
#define CONTACTLAB_EACH_PART _Pragma("GCC unroll 4") for (std::size_t p = 0; p < kLaneParts; ++p)

[[gnu::always_inline]] inline void set_lane(Lanes& v, std::size_t l, double x) {
  part_of(v, l / kPartLanes)[l % kPartLanes] = x;
}

// A register at a time: one copy of the whole struct is a block move through the stack.
[[gnu::always_inline]] inline Lanes load_lanes(const double* from) {
  Lanes v;
  CONTACTLAB_EACH_PART std::memcpy(&part_of(v, p), from + p * kPartLanes, sizeof(LanePart));
  return v;
}
[[gnu::always_inline]] inline void store_lanes(double* to, const Lanes& v) {
  CONTACTLAB_EACH_PART std::memcpy(to + p * kPartLanes, &part_of(v, p), sizeof(LanePart));
}
// Eight given values (constants fold into one vector constant).
[[gnu::always_inline]] inline Lanes lanes_of(const double (&values)[kLanes]) {
  return load_lanes(values);
}
[[gnu::always_inline]] inline LaneMask mask_of(const std::int64_t (&values)[kLanes]) {
  LaneMask m;
  CONTACTLAB_EACH_PART std::memcpy(&part_of(m, p), values + p * kPartLanes, sizeof(MaskPart));
  return m;
}

#if CONTACTLAB_DEM_PARTS != 1  // (a GCC vector has these operators of its own)
#define CONTACTLAB_LANES_ARITHMETIC(op)                                             \
  [[gnu::always_inline]] inline Lanes operator op(const Lanes& a, const Lanes& b) { \
    Lanes r;                                                                        \
    CONTACTLAB_EACH_PART r.part[p] = a.part[p] op b.part[p];                        \
    return r;                                                                       \
  }                                                                                 \
  [[gnu::always_inline]] inline Lanes operator op(const Lanes& a, double b) {       \
    Lanes r;                                                                        \
    CONTACTLAB_EACH_PART r.part[p] = a.part[p] op b;                                \
    return r;                                                                       \
  }                                                                                 \
  [[gnu::always_inline]] inline Lanes operator op(double a, const Lanes& b) {       \
    Lanes r;                                                                        \
    CONTACTLAB_EACH_PART r.part[p] = a op b.part[p];                                \
    return r;                                                                       \
  }                                                                                 \
  [[gnu::always_inline]] inline Lanes& operator op##=(Lanes& a, const Lanes& b) {   \
    CONTACTLAB_EACH_PART a.part[p] = a.part[p] op b.part[p];                        \
    return a;                                                                       \
  }
CONTACTLAB_LANES_ARITHMETIC(+)
CONTACTLAB_LANES_ARITHMETIC(-)
CONTACTLAB_LANES_ARITHMETIC(*)
CONTACTLAB_LANES_ARITHMETIC(/)
#undef CONTACTLAB_LANES_ARITHMETIC

[[gnu::always_inline]] inline Lanes operator-(const Lanes& a) {
  Lanes r;
  CONTACTLAB_EACH_PART r.part[p] = -a.part[p];
  return r;
}

#define CONTACTLAB_LANES_COMPARISON(op)                                                \
  [[gnu::always_inline]] inline LaneMask operator op(const Lanes& a, const Lanes& b) { \
    LaneMask r;                                                                        \
    CONTACTLAB_EACH_PART r.part[p] = a.part[p] op b.part[p];                           \
    return r;                                                                          \
  }                                                                                    \
  [[gnu::always_inline]] inline LaneMask operator op(const Lanes& a, double b) {       \
    LaneMask r;                                                                        \
    CONTACTLAB_EACH_PART r.part[p] = a.part[p] op b;                                   \
    return r;                                                                          \
  }
CONTACTLAB_LANES_COMPARISON(<)
CONTACTLAB_LANES_COMPARISON(>)
CONTACTLAB_LANES_COMPARISON(<=)
CONTACTLAB_LANES_COMPARISON(==)
CONTACTLAB_LANES_COMPARISON(!=)
#undef CONTACTLAB_LANES_COMPARISON

[[gnu::always_inline]] inline LaneMask operator&(const LaneMask& a, const LaneMask& b) {
  LaneMask r;
  CONTACTLAB_EACH_PART r.part[p] = a.part[p] & b.part[p];
  return r;
}
[[gnu::always_inline]] inline LaneMask operator|(const LaneMask& a, const LaneMask& b) {
  LaneMask r;
  CONTACTLAB_EACH_PART r.part[p] = a.part[p] | b.part[p];
  return r;
}
[[gnu::always_inline]] inline LaneMask operator~(const LaneMask& a) {
  LaneMask r;
  CONTACTLAB_EACH_PART r.part[p] = ~a.part[p];
  return r;
}

#endif

// a where the mask is set, b elsewhere: the law's branch-free choices, written once for one
// contact (a bool) and for eight (a mask).
[[gnu::always_inline]] inline double select(bool mask, double a, double b) { return mask ? a : b; }
[[gnu::always_inline]] inline Lanes select(const LaneMask& mask, const Lanes& a, const Lanes& b) {
  Lanes r;
  CONTACTLAB_EACH_PART part_of(r, p) = part_of(mask, p) ? part_of(a, p) : part_of(b, p);
  return r;
}
// v, or +0 in every lane (a bitwise and: no branch).
[[gnu::always_inline]] inline Lanes keep_if(const Lanes& v, bool keep) {
  const MaskPart all = MaskPart{} - static_cast<std::int64_t>(keep);
  Lanes r;
  CONTACTLAB_EACH_PART part_of(r, p) =
      reinterpret_cast<LanePart>(reinterpret_cast<MaskPart>(part_of(v, p)) & all);
  return r;
}
// sum + t where `keep`, else t + 0 (a running sum that starts again from +0: +0 + t is t + 0, and
// x + (t + 0) is x + t for any x but -0, which no sum from +0 is). With AVX-512 one masked add
// on the sum's chain (4 cycles, where the and and the add were 5).
[[gnu::always_inline]] inline Lanes add_if(const Lanes& sum, const Lanes& t, bool keep) {
#if CONTACTLAB_DEM_PARTS == 1 && defined(__x86_64__)
  const Lanes t0 = t + 0.0;
  return reinterpret_cast<Lanes>(_mm512_mask_add_pd(
      reinterpret_cast<__m512d>(t0), static_cast<__mmask8>(-static_cast<int>(keep)),
      reinterpret_cast<__m512d>(sum), reinterpret_cast<__m512d>(t0)));
#else
  return keep_if(sum, keep) + t;
#endif
}

// GCC's __builtin_shuffle(a, [b,] mask): lanes 0..W-1 of a, W..2W-1 of b. Clang has no such
// builtin (its __builtin_shufflevector takes the lane indices as constant arguments, not as a
// vector): there, lane by lane, which clang folds into the same single shuffles once the
// constant mask is inlined. Under GCC the code is the builtin itself.
#if defined(__clang__)
template <class V, class M>
[[gnu::always_inline]] inline V shuffle_lanes(const V& a, const V& b, const M& mask) {
  constexpr std::int64_t kWidth = sizeof(V) / sizeof(double);
  V r;
  for (std::int64_t l = 0; l < kWidth; ++l) {
    const std::int64_t from = mask[l];
    r[l] = from < kWidth ? a[from] : b[from - kWidth];
  }
  return r;
}
template <class V, class M>
[[gnu::always_inline]] inline V shuffle_lanes(const V& a, const M& mask) {
  return shuffle_lanes(a, a, mask);
}
#define CONTACTLAB_SHUFFLE shuffle_lanes
#else
#define CONTACTLAB_SHUFFLE __builtin_shuffle
#endif

// Whether any lane of a mask is set. (The helpers below are templates on the register types
// so that the other widths' constants, in branches not taken, are never formed.)
template <class M>
[[gnu::always_inline]] inline bool any_set_in(M m) {
  if constexpr (sizeof(M) == 64) {
    m |= CONTACTLAB_SHUFFLE(m, M{4, 5, 6, 7, 0, 1, 2, 3});
    m |= CONTACTLAB_SHUFFLE(m, M{2, 3, 0, 1, 6, 7, 4, 5});
    m |= CONTACTLAB_SHUFFLE(m, M{1, 0, 3, 2, 5, 4, 7, 6});
  } else if constexpr (sizeof(M) == 32) {
    m |= CONTACTLAB_SHUFFLE(m, M{2, 3, 0, 1});
    m |= CONTACTLAB_SHUFFLE(m, M{1, 0, 3, 2});
  } else {
    m |= CONTACTLAB_SHUFFLE(m, M{1, 0});
  }
  return m[0] != 0;
}
[[gnu::always_inline]] inline bool any_set(const LaneMask& mask) {
  MaskPart m = part_of(mask, 0);
  for (std::size_t p = 1; p < kLaneParts; ++p) m |= part_of(mask, p);
  return any_set_in(m);
}
[[gnu::always_inline]] inline bool any_false(const LaneMask& m) { return any_set(~m); }

// The W x W transpose of rows r[0..W-1], each a register of W doubles.
template <class P, class M>
[[gnu::always_inline]] inline void transpose_part(const P* r, P* c) {
  if constexpr (sizeof(P) == 64) {
    constexpr M kEven{0, 8, 2, 10, 4, 12, 6, 14}, kOdd{1, 9, 3, 11, 5, 13, 7, 15};
    constexpr M kPairLo{0, 1, 8, 9, 4, 5, 12, 13}, kPairHi{2, 3, 10, 11, 6, 7, 14, 15};
    constexpr M kHalfLo{0, 1, 2, 3, 8, 9, 10, 11}, kHalfHi{4, 5, 6, 7, 12, 13, 14, 15};
    P t[8], u[8];
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
  } else if constexpr (sizeof(P) == 32) {
    constexpr M kEven{0, 4, 2, 6}, kOdd{1, 5, 3, 7}, kLo{0, 1, 4, 5}, kHi{2, 3, 6, 7};
    const P t0 = CONTACTLAB_SHUFFLE(r[0], r[1], kEven);  // r0[0] r1[0] r0[2] r1[2]
    const P t1 = CONTACTLAB_SHUFFLE(r[0], r[1], kOdd);
    const P t2 = CONTACTLAB_SHUFFLE(r[2], r[3], kEven);
    const P t3 = CONTACTLAB_SHUFFLE(r[2], r[3], kOdd);
    c[0] = CONTACTLAB_SHUFFLE(t0, t2, kLo);
    c[1] = CONTACTLAB_SHUFFLE(t1, t3, kLo);
    c[2] = CONTACTLAB_SHUFFLE(t0, t2, kHi);
    c[3] = CONTACTLAB_SHUFFLE(t1, t3, kHi);
  } else {
    c[0] = CONTACTLAB_SHUFFLE(r[0], r[1], M{0, 2});
    c[1] = CONTACTLAB_SHUFFLE(r[0], r[1], M{1, 3});
  }
}

// Rows r[0..7] of eight doubles in, their columns out (c[k][l] = r[l][k]): a transpose of each
// W x W block of registers, put in its mirrored place.
[[gnu::always_inline]] inline void transpose8(const Lanes (&r)[8], Lanes (&c)[8]) {
  constexpr std::size_t kW = kPartLanes;
  for (std::size_t q = 0; q < kLaneParts; ++q) {    // the rows' part: columns q W ..
    for (std::size_t p = 0; p < kLaneParts; ++p) {  // rows p W ..: the columns' part
      LanePart in[kW], out[kW];
      for (std::size_t i = 0; i < kW; ++i) in[i] = part_of(r[p * kW + i], q);
      transpose_part<LanePart, MaskPart>(in, out);
      for (std::size_t j = 0; j < kW; ++j) part_of(c[q * kW + j], p) = out[j];
    }
  }
}

// transpose8's columns stored as they form: column k's first kWidth doubles at to + k stride.
// (transpose8 into an array and then stores went through the stack under AVX2: the array
// spilled and was copied out in 16-byte moves, 6 % of the pair kernel's samples.)
template <std::size_t kWidth = kLanes>
[[gnu::always_inline]] inline void store_transposed(const Lanes (&r)[8], double* to,
                                                    std::size_t stride) {
  constexpr std::size_t kW = kPartLanes;
  static_assert(kWidth == kLanes || kWidth == kLanes / 2);
  if constexpr (kLaneParts == 1) {
    LanePart in[kLanes], c[kLanes];
#pragma GCC unroll 8
    for (std::size_t k = 0; k < kLanes; ++k) in[k] = part_of(r[k], 0);
    transpose_part<LanePart, MaskPart>(in, c);
#pragma GCC unroll 8
    for (std::size_t k = 0; k < kLanes; ++k) std::memcpy(to + k * stride, &c[k], kWidth * 8);
  } else {
#pragma GCC unroll 4
    for (std::size_t q = 0; q < kLaneParts; ++q) {  // the rows' part: columns q W ..
#pragma GCC unroll 4
      for (std::size_t p = 0; p * kW < kWidth; ++p) {  // rows p W ..: the columns' part
        LanePart in[kW], out[kW];
#pragma GCC unroll 4
        for (std::size_t i = 0; i < kW; ++i) in[i] = part_of(r[p * kW + i], q);
        transpose_part<LanePart, MaskPart>(in, out);
#pragma GCC unroll 4
        for (std::size_t j = 0; j < kW; ++j) {
          std::memcpy(to + (q * kW + j) * stride + p * kW, &out[j], sizeof(LanePart));
        }
      }
    }
  }
}

// With one register a row: the columns of four quarter-rows laid side by side, q[p] holding
// row p's four values, then row p + 4's (the tops of a transpose's two halves).
template <class P = LanePart, class M = MaskPart>
[[gnu::always_inline]] inline void columns_of_paired_quarters(const P (&q)[4], Lanes& c0, Lanes& c1,
                                                              Lanes& c2, Lanes& c3) {
  if constexpr (kLaneParts == 1) {
    constexpr M kEven{0, 8, 2, 10, 4, 12, 6, 14}, kOdd{1, 9, 3, 11, 5, 13, 7, 15};
    constexpr M kPairLo{0, 1, 8, 9, 4, 5, 12, 13}, kPairHi{2, 3, 10, 11, 6, 7, 14, 15};
    // even01: c0 of 0 1, c2 of 0 1, c0 of 4 5, ..; odd01: c1 of 0 1, c3 of 0 1, ..
    const P even01 = CONTACTLAB_SHUFFLE(q[0], q[1], kEven);
    const P odd01 = CONTACTLAB_SHUFFLE(q[0], q[1], kOdd);
    const P even23 = CONTACTLAB_SHUFFLE(q[2], q[3], kEven);
    const P odd23 = CONTACTLAB_SHUFFLE(q[2], q[3], kOdd);
    part_of(c0, 0) = CONTACTLAB_SHUFFLE(even01, even23, kPairLo);
    part_of(c2, 0) = CONTACTLAB_SHUFFLE(even01, even23, kPairHi);
    part_of(c1, 0) = CONTACTLAB_SHUFFLE(odd01, odd23, kPairLo);
    part_of(c3, 0) = CONTACTLAB_SHUFFLE(odd01, odd23, kPairHi);
  }
}

// Columns 0..3 of the top halves of rows r[0..7] (lanes 4..7 of each). With one register a
// row, 12 shuffles, not a full transpose's 24 for half of its columns; with several, the
// transpose of the top registers only (the compiler drops the rest of transpose8).
template <class P = LanePart, class M = MaskPart>
[[gnu::always_inline]] inline void top_columns(const Lanes (&r)[8], Lanes& c0, Lanes& c1, Lanes& c2,
                                               Lanes& c3) {
  if constexpr (kLaneParts == 1) {
    constexpr M kTops{4, 5, 6, 7, 12, 13, 14, 15};
    P q[4];  // the tops of rows p and p + 4, side by side
    for (int p = 0; p < 4; ++p)
      q[p] = CONTACTLAB_SHUFFLE(part_of(r[p], 0), part_of(r[p + 4], 0), kTops);
    columns_of_paired_quarters(q, c0, c1, c2, c3);
  } else {
    Lanes c[8];
    transpose8(r, c);
    c0 = c[4];
    c1 = c[5];
    c2 = c[6];
    c3 = c[7];
  }
}

// The square roots of a register's lanes: the set's own instruction (the same IEEE result as
// std::sqrt per lane). Not an `omp simd` loop over the lanes: under -mtune for an Intel server
// core GCC prefers 256-bit vectors in the loops it vectorises, and split each AVX-512 register
// into two halves through the stack: the pair pass's four square roots cost two 32-byte stores
// and a 64-byte load each, a store-forwarding stall (issue #48, a Xeon with AVX-512). A template
// on the register type, so that no other width's intrinsic is formed.
template <class P>
[[gnu::always_inline]] inline P sqrt_part(const P& v) {
#if defined(__x86_64__)
  if constexpr (sizeof(P) == 64) {
    // All lanes through the masked form: GCC 12's _mm512_sqrt_pd passes an undefined vector
    // that -Wmaybe-uninitialized reports.
    return _mm512_mask_sqrt_pd(v, static_cast<__mmask8>(0xFF), v);
  } else if constexpr (sizeof(P) == 32) {
    // GCC's builtins, not the intrinsics: an intrinsic is an always_inline function of the
    // translation unit's own target, which a region of fewer instructions may not inline (the
    // baseline set's "no-avx" under -march=x86-64-v3 did not compile).
    return __builtin_ia32_sqrtpd256(v);
  } else {
    return __builtin_ia32_sqrtpd(v);  // SSE2: the x86-64 baseline
  }
#else
  double in[sizeof(P) / sizeof(double)], out[sizeof(P) / sizeof(double)];
  std::memcpy(in, &v, sizeof in);
  for (std::size_t l = 0; l < sizeof(P) / sizeof(double); ++l) out[l] = std::sqrt(in[l]);
  P r;
  std::memcpy(&r, out, sizeof r);
  return r;
#endif
}

// The square roots of eight lanes.
[[gnu::always_inline]] inline Lanes sqrt_lanes(const Lanes& v) {
  Lanes r;
  CONTACTLAB_EACH_PART { part_of(r, p) = sqrt_part(part_of(v, p)); }
  return r;
}

// The eight lanes, each a whole number in [0, 65535], as 16-bit counts at `to`.
[[gnu::always_inline]] inline void store_counts(std::uint16_t* to, const Lanes& v) {
  using CountPart = std::uint16_t __attribute__((vector_size(sizeof(std::uint16_t) * kPartLanes)));
  CONTACTLAB_EACH_PART {
    const CountPart counts = __builtin_convertvector(part_of(v, p), CountPart);
    std::memcpy(to + p * kPartLanes, &counts, sizeof counts);
  }
}

#undef CONTACTLAB_EACH_PART
#undef CONTACTLAB_DEM_PARTS

}  // CONTACTLAB_DEM_ISA_NAMESPACE(build)
}  // namespace contactlab::dem::detail

#undef CONTACTLAB_SHUFFLE

#endif
