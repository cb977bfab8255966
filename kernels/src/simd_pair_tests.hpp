// The contact test of pair_test.hpp for the homes of one cell against their stencil's slot
// ranges, on SIMD lanes (private to kernels/src; simd.hpp says which target runs it).
#pragma once

#include <cstddef>
#include <cstdint>

#include "contactlab/kernels/pair_test.hpp"
#include "contactlab/kernels/slot_range.hpp"

namespace contactlab::simd {

// Homes tested together: each vector of candidates is loaded once for all of them, and a
// range's loop, its last part-filled vector and the call are paid once. Four: the homes'
// coordinates, the candidates' and the distances fit the 16 vector registers of AVX2.
inline constexpr int kBlockHomes = 4;

// Up to kBlockHomes homes of one cell against the candidate slots of `ranges` (slots = working
// ids: sorted layouts). Coordinates in slot order; d is read only with per-particle diameters.
// ranges[own] is the row holding the homes' cell: a home's candidates there are the slots after
// it (half stencil) or every slot but its own (full). In float, the candidates within `band` of
// touching are decided by the double test on `exact` (pair_test.hpp's FloatBand): the double
// test's contacts.
template <class Real>
struct BlockTask {
  const Real *x, *y, *z, *d;
  Real reach_sq;  // D^2 (without per-particle diameters)
  const SlotRange* ranges;
  int count, own;
  bool half;
  const std::uint32_t* homes;     // their slots, ascending
  int home_count;                 // 1 .. kBlockHomes
  std::uint32_t* const* out;      // out[b]: where home b's partners are written
  std::size_t* found;             // found[b]: how many
  const ExactCoordinates* exact;  // float only
  FloatBand band;                 // float only
};

// Slack past the candidates that a home may write (whole vectors): room the caller leaves.
inline constexpr std::size_t kAppendSlack = 64;

// Writes the slots that touch home b to out[b], in range order and slot order within a range
// (the traversal's candidate order), and their count to found[b]. Writes up to (candidates +
// kAppendSlack) entries per home.
void append_contacts(const BlockTask<double>& task, bool diameters);
void append_contacts(const BlockTask<float>& task, bool diameters);

}  // namespace contactlab::simd
