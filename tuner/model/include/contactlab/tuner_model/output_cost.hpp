// The cost of writing a detection's output (the partner lists of both particles of every
// contact) after the loop, priced per entry.
//
// The loop's constants (schedule_model.hpp) price the pair tests; the rows are written after
// the loop (and, with the half stencil, each contact's reverse entry lands in the other
// particle's row, anywhere in the output). That cost follows the contacts, not the tests: on the
// dense core scene (145 contacts per particle, 0.65 entries per half-stencil test) it was two
// thirds of the half stencil's T_c, while the calibration scenes have far fewer entries per
// test. Priced inside the per-test constant, it made the model choose the half stencil where
// the full one ran 1.4x faster. So the loop constants are fitted to the loop alone and the
// output is priced here, from two measured points per structure and thread count.
#pragma once

#include <cstdint>
#include <span>

namespace contactlab::tuner {

// The assembly's seconds per output entry, per thread (assembly time x threads / entries: each
// thread writes the rows of its own finds), at two output sizes, measured by calibration at
// `threads` threads: a small output (in cache) and a large one (far past the caches).
struct OutputCost {
  int threads = 1;
  double small_bytes = 0.0, small_seconds_per_entry = 0.0;
  double large_bytes = 0.0, large_seconds_per_entry = 0.0;
  friend bool operator==(const OutputCost&, const OutputCost&) = default;
};

// The bytes of an output of `entries` partner entries (32-bit ids).
inline double output_bytes(std::uint64_t entries) { return 4.0 * static_cast<double>(entries); }

// The time to write an output of `entries` entries at `threads` threads: entries / threads x
// c(bytes), with c interpolated linearly in log(bytes) between the two points and held constant
// outside them. Uses the point calibrated at the largest thread count not above `threads` (else
// the smallest), and assumes the entries split evenly over the threads (a prediction past the
// calibrated count assumes the writes scale with the threads). Empty costs or no entries: 0.
double output_seconds(std::span<const OutputCost> costs, std::uint64_t entries, int threads);

}  // namespace contactlab::tuner
