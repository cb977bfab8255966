// A DEM step at thread counts this machine does not have (the report's 8 threads, 16), for
// `dem profile --emulate`: the force pass replayed by the force model (force_model.hpp) with
// costs calibrated at one thread and anchored to the measured one-thread pass, the neighbour
// list and the integration split into a serial and a parallel part from their measured times at
// 1 and P threads. Given a bandwidth curve (a machine file from `contactlab probe` and a stated
// ceiling), the force pass and the integration together take at least the step's bytes over the
// bandwidth P threads draw (step_traffic: the two run as one batched pass over the particles,
// so each particle's data is counted once). Every value is labelled
// emulated by its callers. Not modelled: shared caches as threads are added; the j sides that
// land in another thread's blocks (their cost exists only with several threads: a one-thread
// calibration prices them 0).
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "contactlab/dem/engine.hpp"
#include "contactlab/tuner_dem/force_model.hpp"
#include "contactlab/tuner_model/bandwidth.hpp"

namespace contactlab::dem {

// Seconds per step by phase, measured at one thread count (medians over rounds).
struct MeasuredStep {
  int threads = 1;
  PhaseTimes per_step;
  double step_s = 0.0;  // wall time per step
};

struct EmulatedStep {
  int threads = 1;
  double neighbor_s = 0.0, force_s = 0.0, integrate_s = 0.0;
  // With a bandwidth curve: the bandwidth P threads draw [bytes/s] and the time the step's
  // bytes take at it (0 without a curve).
  double bytes_per_s = 0.0, memory_s = 0.0;
  double step_s() const { return neighbor_s + force_s + integrate_s; }
};

// The bytes the force pass and the drift move a step, from the work counts and the data layout
// (step_emulation.cpp lists the streams): every particle array and list field read and written
// back at least once, and the working set they span (priced against the probe's working set
// that holds it).
struct StepTraffic {
  double bytes = 0.0;
  std::uint64_t footprint_bytes = 0;
};
StepTraffic step_traffic(std::size_t particles, std::uint64_t pairs);

// `one` is the one-thread measurement (the anchor), `widest` the one at the most threads timed
// (the same as `one` on a one-core machine: the neighbour list and integration then count as
// serial). `costs` are calibrated at one thread. With `bandwidth`, the force pass and the
// integration together take at least `traffic`'s bytes at the curve's bandwidth (a roofline;
// where it binds, both parts grow in proportion). Throws
// InputError when `one` is not at one thread or its force pass took no time.
std::vector<EmulatedStep> emulate_steps(const ForceLoopWork& work, const ForceVariant& variant,
                                        const ForceCosts& costs, const MeasuredStep& one,
                                        const MeasuredStep& widest, const std::vector<int>& threads,
                                        const std::optional<tuner::BandwidthCurve>& bandwidth = {},
                                        const StepTraffic& traffic = {});

}  // namespace contactlab::dem
