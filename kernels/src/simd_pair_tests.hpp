// The contact test of pair_test.hpp for whole slot ranges of the sorted layouts, on SIMD lanes
// (private to kernels/src; simd.hpp says which target runs it).
#pragma once

#include <cstddef>
#include <cstdint>

#include "contactlab/kernels/pair_test.hpp"
#include "contactlab/kernels/slot_range.hpp"

namespace contactlab::simd {

// One home against the candidate slots of `ranges` (slots = working ids: sorted layouts).
// Coordinates in slot order; d is read only with per-particle diameters. In float, the
// candidates within `band` of touching are decided by the double test on `exact`
// (pair_test.hpp's FloatBand): the double test's contacts.
template <class Real>
struct RangeTask {
  const Real *x, *y, *z, *d;
  Real xi, yi, zi;
  Real di;        // the home's diameter (with per-particle diameters)
  Real reach_sq;  // D^2 (without them)
  const SlotRange* ranges;
  int count;
  std::uint32_t home;
  const ExactCoordinates* exact;  // float only
  FloatBand band;                 // float only
};

// Slack past the candidates that a call may write (whole vectors): room the caller leaves.
inline constexpr std::size_t kAppendSlack = 64;

// Writes the slots that touch the home to out, in range order and slot order within a range
// (the traversal's candidate order), and returns how many. Writes up to
// (candidates + kAppendSlack) entries.
std::size_t append_contacts(const RangeTask<double>& task, bool diameters, std::uint32_t* out);
std::size_t append_contacts(const RangeTask<float>& task, bool diameters, std::uint32_t* out);

}  // namespace contactlab::simd
