// The bytes a detection moves through the memory system, from its exact work counts and the
// data layout: what `emulate threads --machine` prices each phase's compute against (a phase
// takes at least its bytes over the bandwidth its threads draw: bandwidth.hpp). A stated model,
// not a measurement (docs/emulation.md, "Bandwidth"): caches are assumed to hold what a sweep
// in cell order reuses (the stencil's layers of a sorted scene) and nothing that is reached at
// random (an unsorted scene's candidates, the reordering's gather of staged records).
#pragma once

#include <cstdint>

#include "contactlab/kernels/variant.hpp"
#include "contactlab/tuner_model/schedule_model.hpp"

namespace contactlab::tuner {

struct DetectionWork {
  std::uint64_t particles = 0;
  // Candidates fetched by the loop: a candidate tested against several homes at once (the cell
  // loop: every home of the cell) is fetched once (candidate_fetches).
  std::uint64_t fetches = 0;
  std::uint64_t entries = 0;    // the contact list's entries, both directions
  std::uint64_t cell_keys = 0;  // keys of the grid's numbering: the radix sort's range
  bool diameters = false;       // per-particle diameters: a fourth array
};

struct DetectionTraffic {
  double setup_bytes = 0.0;  // registration (keys, radix sort, cell index) and reordering
  double loop_bytes = 0.0;   // the traversal: coordinates read, finds written
  // After the loop: the rows (the finds read back, every entry written), which the full
  // stencil pays only for the rows its schedule leaves to copy, and the row offsets.
  double rows_bytes = 0.0;
  double offsets_bytes = 0.0;
  // What the detection's arrays occupy: the probe's working set that holds it is the one the
  // bytes are priced against (working_set_for).
  std::uint64_t footprint_bytes = 0;
};

// The 64-byte line a random access moves.
inline constexpr double kLineBytes = 64.0;
// A particle's record staged for the reordering (coordinates and diameter, written past the
// caches): sorted orders only.
inline constexpr double kStagedBytes = 32.0;

// From a loop's exact work: the sum over its iterations of tests / homes (the cell loop tests
// each candidate against every home of its cell; the particle loop has one home).
std::uint64_t candidate_fetches(const WorkView& work);

// Throws std::invalid_argument for no particles or no cell keys.
DetectionTraffic detection_traffic(const Variant& variant, const DetectionWork& work);

}  // namespace contactlab::tuner
