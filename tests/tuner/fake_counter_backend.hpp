// A scripted CounterBackend, so that ThreadCounters' logic is tested on every machine: known
// and countable events, a set-size limit, counts that are a function of (thread, event, region)
// and injected start or stop failures on one thread; it records every call per thread.
#pragma once

#include <algorithm>
#include <functional>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "contactlab/tuner/counter_backend.hpp"

namespace contactlab::test {

struct FakeScript {
  std::string unavailable;             // non-empty: the whole facility is missing, with this reason
  std::vector<std::string> known;      // names that exist; any other is a typo
  std::vector<std::string> countable;  // known names that can be counted here
  std::size_t max_events = 64;         // events one set can hold
  int fail_start_thread = -1;          // start fails on this thread (every region)
  int fail_stop_thread = -1;           // stop fails on this thread (every region)
  // The count of `event` on `thread` in region `region` (0 for the first prepared region).
  std::function<long long(int thread, const std::string& event, int region)> value =
      [](int thread, const std::string& event, int region) {
        return 1000LL * (region + 1) + 10LL * (thread + 1) + static_cast<long long>(event.size());
      };
};

class FakeCounterBackend final : public tuner::CounterBackend {
 public:
  static constexpr int kStartFailure = -101;
  static constexpr int kStopFailure = -102;

  // What one region saw, per thread (each thread writes only its own entries).
  struct RegionLog {
    std::vector<std::string> events;
    std::vector<int> starts, stops;
    std::vector<std::thread::id> start_thread, stop_thread;
  };

  explicit FakeCounterBackend(FakeScript script) : script_(std::move(script)) {}

  std::string name() const override { return "fake"; }
  std::string unavailable_reason() const override { return script_.unavailable; }

  std::optional<std::string> unknown_event(const std::string& event) const override {
    if (contains(script_.known, event)) return std::nullopt;
    return "unknown fake event '" + event + "'";
  }

  std::optional<std::string> try_events(const std::vector<std::string>& events) override {
    ++tries;
    for (const auto& e : events) {
      if (!contains(script_.countable, e)) return e + ": not countable here (scripted)";
    }
    if (events.size() > script_.max_events) {
      return "add: more than " + std::to_string(script_.max_events) + " events in one set";
    }
    return std::nullopt;
  }

  void prepare(const std::vector<std::string>& events, int threads) override {
    RegionLog log;
    log.events = events;
    log.starts.assign(threads, 0);
    log.stops.assign(threads, 0);
    log.start_thread.assign(threads, {});
    log.stop_thread.assign(threads, {});
    regions.push_back(std::move(log));
  }

  tuner::CounterStatus start(int thread) noexcept override {
    RegionLog& log = regions.back();
    ++log.starts[thread];
    log.start_thread[thread] = std::this_thread::get_id();
    if (thread == script_.fail_start_thread) return {"start", kStartFailure};
    return {};
  }

  tuner::CounterStatus stop(int thread, std::span<long long> values) noexcept override {
    RegionLog& log = regions.back();
    ++log.stops[thread];
    log.stop_thread[thread] = std::this_thread::get_id();
    if (thread == script_.fail_stop_thread) return {"stop", kStopFailure};
    const int region = static_cast<int>(regions.size()) - 1;
    for (std::size_t e = 0; e < log.events.size(); ++e) {
      values[e] = script_.value(thread, log.events[e], region);
    }
    return {};
  }

  std::string describe(int code) const override {
    if (code == kStartFailure) return "scripted start failure";
    if (code == kStopFailure) return "scripted stop failure";
    return "fake error " + std::to_string(code);
  }

  // Observations, read by the tests after the region.
  int tries = 0;
  std::vector<RegionLog> regions;

 private:
  static bool contains(const std::vector<std::string>& list, const std::string& s) {
    return std::find(list.begin(), list.end(), s) != list.end();
  }
  FakeScript script_;
};

}  // namespace contactlab::test
