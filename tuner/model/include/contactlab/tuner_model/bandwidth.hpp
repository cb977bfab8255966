// Memory bandwidth against thread count, for emulations that price a phase by the bytes it moves
// as well as by its compute (docs/emulation.md, "Bandwidth"). A machine file (`contactlab
// probe`) gives the bandwidth measured at each thread count the machine has, for a few working
// sets; beyond the last measured count a stated law takes over: a saturating curve through the
// last point towards a ceiling that the user states with its source (a vendor figure, a
// measurement on the larger machine). A phase then takes the longer of its compute time and its
// bytes over the bandwidth its threads draw (a roofline: the two overlap).
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace contactlab::tuner {

class BandwidthCurve {
 public:
  // measured: (threads, bytes/s) with threads >= 1, ascending and distinct, bytes/s > 0, at least
  // one point; ceiling_bytes_per_s: > 0, or 0 for no stated ceiling (the last point holds beyond
  // the measured counts). Throws std::invalid_argument otherwise, naming the problem.
  BandwidthCurve(std::vector<std::pair<int, double>> measured, double ceiling_bytes_per_s);

  // Bandwidth at `threads` (>= 1): the measured points, linear between them; below the first,
  // the first point scaled by threads / its threads; beyond the last (P_m, B_m), with ceiling C
  // above B_m, the curve C P / (P + K) with K = P_m (C / B_m - 1), which passes through the last
  // point, rises with P and tends to C; with C at or below B_m (or none), B_m.
  double at(int threads) const;

  const std::vector<std::pair<int, double>>& measured() const { return measured_; }
  double ceiling() const { return ceiling_; }

 private:
  std::vector<std::pair<int, double>> measured_;
  double ceiling_ = 0.0;
};

// A phase's time at a thread count: the longer of its compute time and the time to move `bytes`
// at `bytes_per_s` (throws std::invalid_argument for a negative time or bytes, or bandwidth <= 0).
double roofline_seconds(double compute_s, double bytes, double bytes_per_s);

// The working set a phase needs priced against: of the probed working-set sizes (ascending),
// the index of the smallest at least `footprint_bytes`, else the largest. Throws
// std::invalid_argument for no sizes.
std::size_t working_set_for(const std::vector<std::uint64_t>& probed_bytes,
                            std::uint64_t footprint_bytes);

}  // namespace contactlab::tuner
