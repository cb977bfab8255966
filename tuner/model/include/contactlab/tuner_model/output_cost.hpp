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
// output is priced here.
//
// Per entry, the half stencil's reverse entries cost more where one home's finds reach more
// rows (more cache lines than L1, then than L2, written once each): measured at 2 threads,
// 1.8 ns per entry per thread where cells hold at most 53 particles, 2.2 ns with up to 350-1,700
// (the paper's clustering, an off-centre blob), 3.1 ns with 5,100 (the dense core); not the
// output's size (a 29 MB and a 115 MB uniform output cost the same). So the cost is measured at
// two degrees: the entry-weighted mean degree (sum k^2 / sum k over the particles' contact
// counts k, the degree of the typical entry's particle) of two calibration scenes.
#pragma once

#include <cstdint>
#include <span>

namespace contactlab::tuner {

// The assembly's seconds per output entry, per thread (assembly time x threads / entries: each
// thread writes the rows of its own finds), measured by calibration at `threads` threads on a
// scene of low entry-weighted degree and on one of high degree.
struct OutputCost {
  int threads = 1;
  double low_degree = 0.0, low_seconds_per_entry = 0.0;
  double high_degree = 0.0, high_seconds_per_entry = 0.0;
  // What passing a reverse entry on to another thread's row costs, in entries written: where
  // the half stencil's threads pass them on (passes_reverse_entries_on), (P - 1) / P of the
  // entries are passed, and the output takes 1 + exchange (P - 1) / P times as long. Measured
  // at `threads` from a dynamic deal's assembly against the block's; 0 where not measured (the
  // full stencil, one thread, caches from before it).
  double exchange = 0.0;
  friend bool operator==(const OutputCost&, const OutputCost&) = default;
};

// What the model knows of an output before any timed run: its entries (two per contact) and
// their entry-weighted mean degree.
struct OutputEstimate {
  std::uint64_t entries = 0;
  double degree = 0.0;
};

// The time to write the output at `threads` threads: entries / threads x c(degree), with c
// interpolated linearly in log(degree) between the two points and held constant outside them.
// Uses the point calibrated at the largest thread count not above `threads` (else the
// smallest), and assumes the entries split evenly over the threads (a prediction past the
// calibrated count assumes the writes scale with the threads). Empty costs or no entries: 0.
double output_seconds(std::span<const OutputCost> costs, const OutputEstimate& output, int threads);

// 1 + exchange (P - 1) / P at P = `threads`, with the exchange of the point output_seconds uses:
// the factor on the output where the half stencil's threads pass their reverse entries on (the
// 16-core Xeon's static,200 assembly, whose threads do, ran 0.25 of its one-thread time at 16
// threads where the block's rows, its homes, took 0.39 and an even split would take 0.06).
// 1 for empty costs.
double exchange_factor(std::span<const OutputCost> costs, int threads);

// The exchange from the assembly's seconds at `threads` > 1 under a deal that passes the
// entries on and under the block: the passed share (threads - 1) / threads made the difference.
// 0 where the times are not positive or the passing deal was no slower.
double fit_exchange(double passing_s, double block_s, int threads);

}  // namespace contactlab::tuner
