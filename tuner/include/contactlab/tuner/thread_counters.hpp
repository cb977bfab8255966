// Event counts of the detection loop, one event set per OpenMP thread, over any CounterBackend:
// the counting logic shared by PAPI and the scripted backend of the tests.
//
// Degrades like Google Benchmark's perf counters: where the events cannot be counted, the
// observer does nothing and its record says available: false with the backend's reason; the
// run itself always completes.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "contactlab/kernels/detector.hpp"
#include "contactlab/tuner/counter_backend.hpp"
#include "contactlab/tuner/counter_record.hpp"

namespace contactlab::tuner {

// One way to compute a miss rate: 100 * sum(numerator) / sum(denominator). The candidates are
// tried in order, because presets differ between CPUs (many lack PAPI_LST_INS or PAPI_L2_DCA).
struct PapiFormula {
  std::vector<std::string> numerator;
  std::vector<std::string> denominator;
  std::string basis;                        // "load/store instructions", "accesses", "loads"
  std::string text() const;                 // "100 * PAPI_L1_DCM / PAPI_LST_INS"
  std::vector<std::string> events() const;  // numerator, then denominator
};
const std::vector<PapiFormula>& papi_l1_formulas();
const std::vector<PapiFormula>& papi_l2_formulas();

class ThreadCounters : public DetectionObserver {
 public:
  // `events` empty: the L1 and L2 formulas, the first candidate of each level whose events can
  // be counted in one set with the other level's. Otherwise exactly those events (rates are
  // derived when they contain a whole formula). Throws InputError for a name the backend does
  // not know (a typo); a known event that cannot be counted here is recorded unavailable.
  ThreadCounters(std::unique_ptr<CounterBackend> backend, std::vector<std::string> events,
                 std::vector<PapiFormula> l1_formulas = papi_l1_formulas(),
                 std::vector<PapiFormula> l2_formulas = papi_l2_formulas());
  ~ThreadCounters() override;
  ThreadCounters(const ThreadCounters&) = delete;
  ThreadCounters& operator=(const ThreadCounters&) = delete;

  bool available() const { return available_; }
  const std::vector<std::string>& event_names() const { return names_; }

  // The detector calls these around its detection loop; thread_begin and thread_end run on
  // every OpenMP thread of the region and never throw: failures are kept per thread and
  // reported by region_end, which makes the record unavailable ("thread T: step: reason").
  void region_begin(int threads) override;
  void thread_begin(int thread) override;
  void thread_end(int thread) override;
  void region_end() override;

  // Totals over every counted region and thread, per-thread totals and the formulas' rates.
  CounterRecord record() const;

 private:
  struct Slot {  // one thread's share of the current region
    bool began = false;
    bool ended = false;
    CounterStatus status;
    std::vector<long long> values;
  };

  std::unique_ptr<CounterBackend> backend_;
  std::vector<std::string> names_;
  std::optional<PapiFormula> l1_, l2_;
  bool available_ = false;
  std::string reason_;
  std::vector<std::string> notes_;
  std::vector<Slot> slots_;                         // this region's threads
  std::vector<std::vector<std::uint64_t>> totals_;  // [thread][event] over counted regions
  int counted_runs_ = 0;
  bool in_region_ = false;
};

}  // namespace contactlab::tuner
