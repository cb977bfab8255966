// The DEM kernels' eight lanes (private to the engine, src/lanes.hpp) at every register width
// they are built for, in one binary: one register of eight doubles (the AVX-512 form), two of
// four (AVX2) and four of two (SSE2), each included in a namespace of its own as engine_isa.cpp
// does. Each width must give every lane what the scalar operation gives: the transposes put
// each element in its mirrored place, the selects, masks and tests are per lane, the sqrt is
// IEEE's, the counts exact. The kernels' bit-identity across instruction sets rests on it.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>

#define CONTACTLAB_DEM_ISA_NAMESPACE(name) namespace one_register
#define CONTACTLAB_DEM_LANE_PARTS 1
#include "lanes.hpp"
#undef CONTACTLAB_DEM_ISA_NAMESPACE
#undef CONTACTLAB_DEM_LANE_PARTS

#define CONTACTLAB_DEM_ISA_TOGGLE  // the header once more
#define CONTACTLAB_DEM_ISA_NAMESPACE(name) namespace two_registers
#define CONTACTLAB_DEM_LANE_PARTS 2
#include "lanes.hpp"
#undef CONTACTLAB_DEM_ISA_NAMESPACE
#undef CONTACTLAB_DEM_LANE_PARTS

#undef CONTACTLAB_DEM_ISA_TOGGLE  // and once more
#define CONTACTLAB_DEM_ISA_NAMESPACE(name) namespace four_registers
#define CONTACTLAB_DEM_LANE_PARTS 4
#include "lanes.hpp"

namespace contactlab::dem::detail {
namespace {

// Each width's checks, written once: `ns` is the width's namespace.
#define CONTACTLAB_LANES_CHECKS(ns)                                                         \
  TEST(DemLanes, TransposeMirrorsEveryElement_##ns) {                                       \
    ns::Lanes rows[8], columns[8];                                                          \
    double values[8][8];                                                                    \
    for (int r = 0; r < 8; ++r)                                                             \
      for (int c = 0; c < 8; ++c) values[r][c] = 10.0 * r + c;                              \
    for (int r = 0; r < 8; ++r) rows[r] = ns::load_lanes(values[r]);                        \
    ns::transpose8(rows, columns);                                                          \
    for (int k = 0; k < 8; ++k)                                                             \
      for (int l = 0; l < 8; ++l) EXPECT_EQ(columns[k][l], values[l][k]) << k << ", " << l; \
    ns::Lanes c0, c1, c2, c3;                                                               \
    ns::top_columns(rows, c0, c1, c2, c3);                                                  \
    for (int l = 0; l < 8; ++l) {                                                           \
      EXPECT_EQ(c0[l], values[l][4]);                                                       \
      EXPECT_EQ(c1[l], values[l][5]);                                                       \
      EXPECT_EQ(c2[l], values[l][6]);                                                       \
      EXPECT_EQ(c3[l], values[l][7]);                                                       \
    }                                                                                       \
  }                                                                                         \
  TEST(DemLanes, StoredTransposeWritesEachColumnAtItsStride_##ns) {                         \
    ns::Lanes rows[8];                                                                      \
    double values[8][8];                                                                    \
    for (int r = 0; r < 8; ++r)                                                             \
      for (int c = 0; c < 8; ++c) values[r][c] = 10.0 * r + c;                              \
    for (int r = 0; r < 8; ++r) rows[r] = ns::load_lanes(values[r]);                        \
    constexpr int kStride = 12; /* a kin block: 8 + 4 doubles, the 4 from the half width */ \
    double out[8 * kStride];                                                                \
    for (double& x : out) x = -1.0;                                                         \
    ns::store_transposed(rows, out, kStride);                                               \
    ns::store_transposed<4>(rows, out + 8, kStride);                                        \
    for (int k = 0; k < 8; ++k) {                                                           \
      for (int l = 0; l < 8; ++l) EXPECT_EQ(out[k * kStride + l], values[l][k]) << k << l;  \
      for (int l = 0; l < 4; ++l) EXPECT_EQ(out[k * kStride + 8 + l], values[l][k]) << k;   \
    }                                                                                       \
  }                                                                                         \
  TEST(DemLanes, OperationsAreTheScalarOnesLaneByLane_##ns) {                               \
    const double a_in[8] = {1.5, -2.0, 0.0, -0.0, 1e300, 3.0, 7.25, -1e-300};               \
    const double b_in[8] = {0.5, 4.0, -1.0, 2.0, 1e300, 3.0, -7.25, 2.0};                   \
    const ns::Lanes a = ns::load_lanes(a_in), b = ns::load_lanes(b_in);                     \
    const ns::Lanes sum = a + b, prod = a * 3.0, quot = 1.0 / b, neg = -a;                  \
    const ns::Lanes picked = ns::select((a < b) | (a == 3.0), a * b, ns::Lanes{} + 9.0);    \
    const ns::Lanes root = ns::sqrt_lanes(b);                                               \
    for (int l = 0; l < 8; ++l) {                                                           \
      EXPECT_EQ(sum[l], a_in[l] + b_in[l]);                                                 \
      EXPECT_EQ(prod[l], a_in[l] * 3.0);                                                    \
      EXPECT_EQ(quot[l], 1.0 / b_in[l]);                                                    \
      EXPECT_EQ(std::signbit(neg[l]), !std::signbit(a_in[l]));                              \
      const bool take = a_in[l] < b_in[l] || a_in[l] == 3.0;                                \
      EXPECT_EQ(picked[l], take ? a_in[l] * b_in[l] : 9.0) << l;                            \
      if (b_in[l] < 0)                                                                      \
        EXPECT_TRUE(std::isnan(root[l]));                                                   \
      else                                                                                  \
        EXPECT_EQ(root[l], std::sqrt(b_in[l]));                                             \
    }                                                                                       \
    EXPECT_TRUE(ns::any_set(a == 7.25));                                                    \
    EXPECT_FALSE(ns::any_set(a == 8.0));                                                    \
    EXPECT_TRUE(ns::any_false(a < 1e300));                                                  \
    EXPECT_FALSE(ns::any_false(a <= 1e300));                                                \
    for (int l = 0; l < 8; ++l) {                                                           \
      double one_set[8] = {};                                                               \
      one_set[l] = 1.0;                                                                     \
      EXPECT_TRUE(ns::any_set(ns::load_lanes(one_set) != 0.0)) << l;                        \
    }                                                                                       \
  }                                                                                         \
  TEST(DemLanes, KeepMaskAndCountsAreExact_##ns) {                                          \
    const double in[8] = {1, 2, 3, 4, 65535, 6, 0, 8};                                      \
    const ns::Lanes v = ns::load_lanes(in);                                                 \
    const ns::Lanes kept = ns::keep_if(v, true), dropped = ns::keep_if(-v, false);          \
    const ns::Lanes masked = ns::select(ns::mask_of({-1, 0, -1, 0, -1, 0, -1, 0}), v, -v);  \
    std::uint16_t counts[8];                                                                \
    ns::store_counts(counts, v);                                                            \
    for (int l = 0; l < 8; ++l) {                                                           \
      EXPECT_EQ(kept[l], in[l]);                                                            \
      EXPECT_EQ(dropped[l], 0.0);                                                           \
      EXPECT_FALSE(std::signbit(dropped[l]));                                               \
      EXPECT_EQ(masked[l], l % 2 == 0 ? in[l] : -in[l]);                                    \
      EXPECT_EQ(counts[l], static_cast<std::uint16_t>(in[l]));                              \
    }                                                                                       \
    ns::Lanes set = ns::lanes_of({0, 0, 0, 0, 0, 0, 0, 0});                                 \
    ns::set_lane(set, 5, 2.5);                                                              \
    for (int l = 0; l < 8; ++l) EXPECT_EQ(set[l], l == 5 ? 2.5 : 0.0);                      \
  }

CONTACTLAB_LANES_CHECKS(one_register)
CONTACTLAB_LANES_CHECKS(two_registers)
CONTACTLAB_LANES_CHECKS(four_registers)

TEST(DemLanes, EachWidthHoldsEightDoublesInItsRegisters) {
  EXPECT_EQ(one_register::kLaneParts * one_register::kPartLanes, 8u);
  EXPECT_EQ(two_registers::kPartLanes, 4u);
  EXPECT_EQ(four_registers::kPartLanes, 2u);
  EXPECT_EQ(sizeof(two_registers::Lanes), 64u);
  EXPECT_EQ(sizeof(four_registers::Lanes), 64u);
}

}  // namespace
}  // namespace contactlab::dem::detail
