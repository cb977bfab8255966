// What a counting facility (PAPI, or a scripted one in tests) must offer to ThreadCounters.
//
// The per-thread counting logic (formula choice, event sets per OpenMP thread, sums, rates,
// failures) lives in ThreadCounters and is the same for every facility; a backend only answers
// questions about event names and counts on one thread. Keeping the interface this small is
// what lets the logic be tested on every machine with a deterministic backend, while the real
// PAPI backend is tested only where PAPI can count.
#pragma once

#include <optional>
#include <span>
#include <string>
#include <vector>

namespace contactlab::tuner {

// The outcome of a call made inside the parallel region. No allocation, so that building it
// cannot throw there; the code is turned into text by CounterBackend::describe afterwards.
struct CounterStatus {
  const char* step = nullptr;  // the call that failed (a string literal); nullptr: success
  int code = 0;                // the backend's error code
  bool ok() const { return step == nullptr; }
};

class CounterBackend {
 public:
  virtual ~CounterBackend() = default;

  // The record's `source`, e.g. "papi".
  virtual std::string name() const = 0;

  // Why nothing at all can be counted here (library missing or not initialised); "" when the
  // facility works. With a reason, no other question is asked.
  virtual std::string unavailable_reason() const = 0;

  // Why `event` is not an event here at all (a typo: the caller reports an input error), or
  // nullopt when it is known, or cannot be ruled out (its component is disabled, so its
  // events cannot be listed). Known but not countable is try_events' answer, not this one.
  virtual std::optional<std::string> unknown_event(const std::string& event) const = 0;

  // Whether `events` can be counted together in one set here, asked outside any region: nullopt
  // when yes, else the first failure ("EVENT: reason" or "step: reason").
  virtual std::optional<std::string> try_events(const std::vector<std::string>& events) = 0;

  // Before a region of `threads` threads, outside it: the events every thread will count (a
  // set that try_events accepted) and the per-thread state to size.
  virtual void prepare(const std::vector<std::string>& events, int threads) = 0;

  // Inside the region, on OpenMP thread `thread` (0 <= thread < threads), concurrently with the
  // other threads (each with its own index). start opens the thread's set and starts it; on
  // failure it releases what it acquired. stop, called only after a successful start, stops,
  // writes one value per prepared event into `values` and releases the set.
  virtual CounterStatus start(int thread) noexcept = 0;
  virtual CounterStatus stop(int thread, std::span<long long> values) noexcept = 0;

  // The text of an error code of start or stop, asked after the region.
  virtual std::string describe(int code) const = 0;
};

}  // namespace contactlab::tuner
