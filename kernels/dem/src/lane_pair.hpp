// Two groups of eight lanes as one value of the pair law (private to src/): each operation on
// a TwoGroups is that operation on both groups, one after the other, so the law on it is two
// independent dependency chains interleaved instruction by instruction.
//
// Why: a group of eight pairs is one long chain through the law (two square roots and two
// divisions in a row), and with AVX-512 one group's instructions (about 460) fill most of what
// the core holds in flight, so the next group's chain could hardly start before this one
// ended: the pair loop ran at about 1.5 instructions a cycle. Two groups interleaved ran the
// bed's step 1.11x faster (issue #48). With AVX2 a Lanes value is already two registers (two
// chains) and 16 registers hold less: a second group there cost 6 % in spills, and three or
// four chains as an array of groups was slower on both (the arrays stayed on the stack).
// Each lane computes what it computes alone: the groups never mix.
// Compiled once per instruction set (dem_isa.hpp): a toggle, no include guard.

#include "dem_isa.hpp"
#include "lanes.hpp"

#if defined(CONTACTLAB_DEM_LANE_PAIR_TOGGLE) == defined(CONTACTLAB_DEM_ISA_TOGGLE)
#ifdef CONTACTLAB_DEM_LANE_PAIR_TOGGLE
#undef CONTACTLAB_DEM_LANE_PAIR_TOGGLE
#else
#define CONTACTLAB_DEM_LANE_PAIR_TOGGLE
#endif

namespace contactlab::dem::detail {
CONTACTLAB_DEM_ISA_NAMESPACE(build) {

// Named members, not an array: GCC kept an array of groups in memory.
struct TwoMasks {
  LaneMask a, b;
};
struct TwoGroups {
  Lanes a, b;
};

// An operator on both groups: (two groups, two groups) and (two groups, double), giving R.
// NOLINTBEGIN(bugprone-macro-parentheses): op is an operator's token, which parentheses break
#define CONTACTLAB_TWO_GROUPS_BINARY(op, R)                                             \
  [[gnu::always_inline]] inline R operator op(const TwoGroups& x, const TwoGroups& y) { \
    return {x.a op y.a, x.b op y.b};                                                    \
  }                                                                                     \
  [[gnu::always_inline]] inline R operator op(const TwoGroups& x, double y) {           \
    return {x.a op y, x.b op y};                                                        \
  }
// Arithmetic also takes a double on the left, and has its assignment form.
#define CONTACTLAB_TWO_GROUPS_ARITHMETIC(op)                                                  \
  CONTACTLAB_TWO_GROUPS_BINARY(op, TwoGroups)                                                 \
  [[gnu::always_inline]] inline TwoGroups operator op(double x, const TwoGroups& y) {         \
    return {x op y.a, x op y.b};                                                              \
  }                                                                                           \
  [[gnu::always_inline]] inline TwoGroups& operator op##=(TwoGroups& x, const TwoGroups& y) { \
    x.a = x.a op y.a;                                                                         \
    x.b = x.b op y.b;                                                                         \
    return x;                                                                                 \
  }
// NOLINTEND(bugprone-macro-parentheses)
CONTACTLAB_TWO_GROUPS_ARITHMETIC(+)
CONTACTLAB_TWO_GROUPS_ARITHMETIC(-)
CONTACTLAB_TWO_GROUPS_ARITHMETIC(*)
CONTACTLAB_TWO_GROUPS_ARITHMETIC(/)
CONTACTLAB_TWO_GROUPS_BINARY(<, TwoMasks)
CONTACTLAB_TWO_GROUPS_BINARY(>, TwoMasks)
CONTACTLAB_TWO_GROUPS_BINARY(!=, TwoMasks)
#undef CONTACTLAB_TWO_GROUPS_ARITHMETIC
#undef CONTACTLAB_TWO_GROUPS_BINARY

[[gnu::always_inline]] inline TwoGroups operator-(const TwoGroups& x) { return {-x.a, -x.b}; }

[[gnu::always_inline]] inline TwoMasks operator&(const TwoMasks& x, const TwoMasks& y) {
  return {x.a & y.a, x.b & y.b};
}
[[gnu::always_inline]] inline TwoMasks operator|(const TwoMasks& x, const TwoMasks& y) {
  return {x.a | y.a, x.b | y.b};
}
[[gnu::always_inline]] inline TwoGroups select(const TwoMasks& mask, const TwoGroups& x,
                                               const TwoGroups& y) {
  return {select(mask.a, x.a, y.a), select(mask.b, x.b, y.b)};
}
[[gnu::always_inline]] inline TwoGroups sqrt_of(const TwoGroups& x) {
  return {sqrt_lanes(x.a), sqrt_lanes(x.b)};
}

}  // CONTACTLAB_DEM_ISA_NAMESPACE(build)
}  // namespace contactlab::dem::detail

#endif
