// Hardware (or software) event counts through PAPI, one event set per OpenMP thread, started
// and stopped inside the parallel region around the detection loop and summed.
//
// Degrades like Google Benchmark's perf counters: where PAPI is missing, or the events cannot
// be added or started (virtual machines without a PMU), the observer does nothing and its
// record says available: false with PAPI's reason; the run itself always completes.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "contactlab/kernels/detector.hpp"
#include "contactlab/tuner/counter_record.hpp"

namespace contactlab::tuner {

// One way to compute a miss rate: 100 * sum(numerator) / sum(denominator). The candidates are
// tried in order, because presets differ between CPUs (many lack PAPI_LST_INS or PAPI_L2_DCA).
struct PapiFormula {
  std::vector<std::string> numerator;
  std::vector<std::string> denominator;
  std::string basis;         // "load/store instructions", "accesses", "loads"
  std::string text() const;  // "100 * PAPI_L1_DCM / PAPI_LST_INS"
};
const std::vector<PapiFormula>& papi_l1_formulas();
const std::vector<PapiFormula>& papi_l2_formulas();

struct PapiEventProbe {
  std::string name;
  bool usable = false;  // could be added to an event set and started on this machine
  std::string reason;   // PAPI's error when not
};

// What PAPI offers here; PAPI is initialised (library and threads) on the first call.
struct PapiInfo {
  bool built_with_papi = false;
  bool initialized = false;
  std::string version;  // of the library in use
  std::string error;    // why initialisation failed
  int hardware_counters = 0;
  std::vector<std::string> components;       // active components
  std::vector<std::string> presets_listed;   // presets PAPI lists as available (may still fail)
  std::vector<PapiEventProbe> cache_events;  // every event of the miss-rate formulas, tried
};
const PapiInfo& papi_info();

class PapiCounters final : public DetectionObserver {
 public:
  // `events` empty: the L1 and L2 data-cache miss formulas, first usable candidate of each.
  // Otherwise exactly those events (rates are derived when they form a known formula).
  // Throws InputError for a name that is neither a PAPI preset nor a native event here (a
  // typo); a known event that this machine cannot count is recorded as unavailable instead.
  explicit PapiCounters(std::vector<std::string> events = {});
  ~PapiCounters() override;
  PapiCounters(const PapiCounters&) = delete;
  PapiCounters& operator=(const PapiCounters&) = delete;

  bool available() const;
  const std::vector<std::string>& event_names() const;

  void region_begin(int threads) override;
  void thread_begin(int thread) override;
  void thread_end(int thread) override;
  void region_end() override;

  // Totals over every counted region and thread.
  CounterRecord record() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace contactlab::tuner
