// Hardware (or software) event counts through PAPI: ThreadCounters over the PAPI backend, one
// event set per OpenMP thread, started and stopped inside the parallel region and summed.
//
// Where PAPI is missing, its component is disabled (virtual machines without a PMU) or the
// events cannot be added or started, the record says available: false with PAPI's reason; the
// run itself always completes.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "contactlab/tuner/counter_backend.hpp"
#include "contactlab/tuner/thread_counters.hpp"

namespace contactlab::tuner {

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

// Whether PAPI can count `events` together on this machine, asked of PAPI the way papi_info
// probes (add to one event set, start, stop) after checking each event's component. The tests
// of the real backend skip with `reason` when not countable, and never on their own result.
struct PapiProbe {
  bool countable = false;
  std::string reason;  // why not, e.g. "perf::TASK-CLOCK: PAPI component perf_event is
                       // disabled: Error libpfm4 no default PMU found"; empty when countable
};
PapiProbe papi_probe(const std::vector<std::string>& events);

// Why the PAPI component that would count `event` is disabled here ("PAPI component perf_event
// is disabled: Error libpfm4 no default PMU found"), found by the native prefix ("perf::") or
// the event's code; "" when it is enabled, unknown, or PAPI is missing.
std::string papi_disabled_component(const std::string& event);

// The real backend (PAPI_add_events / PAPI_start / PAPI_stop per thread). In a build without
// PAPI every answer is "built without PAPI".
std::unique_ptr<CounterBackend> make_papi_backend();

class PapiCounters final : public ThreadCounters {
 public:
  // `events` empty: the L1 and L2 data-cache miss formulas, first usable candidate of each.
  // Otherwise exactly those events (rates are derived when they form a known formula).
  // Throws InputError for a name that is neither a PAPI preset nor a native event here (a
  // typo); a known event that this machine cannot count, or an event of a component PAPI
  // reports disabled, is recorded as unavailable instead, with PAPI's reason.
  explicit PapiCounters(std::vector<std::string> events = {});
};

}  // namespace contactlab::tuner
