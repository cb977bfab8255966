// The per-thread PAPI path, proved with software events that exist even where the machine
// exposes no hardware counters (virtual machines): perf::TASK-CLOCK and perf::PAGE-FAULTS.
#include <gtest/gtest.h>

#include "contactlab/kernels/error.hpp"
#include "contactlab/tuner/measure.hpp"
#include "contactlab/tuner/papi_counters.hpp"
#include "tuner_test_support.hpp"

namespace contactlab::tuner {
namespace {

const std::vector<std::string> kSoftware{"perf::TASK-CLOCK", "perf::PAGE-FAULTS"};

// GTEST_SKIP returns from the function it is in, so this is a macro.
#define SKIP_WITHOUT_PAPI() \
  if (!papi_info().initialized) GTEST_SKIP() << "no PAPI here: " << papi_info().error

const EventCount& event(const CounterRecord& r, const std::string& name) {
  for (const auto& e : r.events) {
    if (e.name == name) return e;
  }
  throw std::runtime_error("no event " + name);
}

// One detection with a fresh detector (its buffers grow inside the loop) under the counters.
CounterRecord count_detection(std::uint64_t n, int threads) {
  const SceneSpec spec = test::small_clustered(n, 0.01);
  const Scene scene = generate_scene(spec);
  PapiCounters counters(kSoftware);
  if (!counters.available()) return counters.record();
  ContactDetector detector;
  DetectOptions options{parse_variant("particle/sorted/static"), spec.diameter, threads, &counters};
  detector.run(scene, options);
  return counters.record();
}

TEST(Papi, InitialisesAndReportsItsVersion) {
  SKIP_WITHOUT_PAPI();
  EXPECT_FALSE(papi_info().version.empty());
  EXPECT_FALSE(papi_info().cache_events.empty());
}

TEST(Papi, TaskClockCoversEveryThread) {
  SKIP_WITHOUT_PAPI();
  const CounterRecord r = count_detection(20000, 2);
  if (!r.available) GTEST_SKIP() << "software events not countable here: " << r.reason;
  EXPECT_EQ(r.source, "papi");
  EXPECT_EQ(r.counted_runs, 1);
  const EventCount& clock = event(r, "perf::TASK-CLOCK");
  ASSERT_EQ(clock.per_thread.size(), 2u);
  std::uint64_t sum = 0;
  for (const auto v : clock.per_thread) {
    EXPECT_GT(v, 0u) << "a thread's event set counted nothing";
    sum += v;
  }
  EXPECT_EQ(sum, clock.total);
  EXPECT_FALSE(r.l1_miss_percent.has_value());  // no cache events asked for: no invented rate
}

TEST(Papi, PageFaultsRiseWithN) {
  SKIP_WITHOUT_PAPI();
  const CounterRecord small = count_detection(2000, 2);
  if (!small.available) GTEST_SKIP() << "software events not countable here: " << small.reason;
  const CounterRecord large = count_detection(200000, 2);
  ASSERT_TRUE(large.available) << large.reason;
  EXPECT_GT(event(large, "perf::PAGE-FAULTS").total, event(small, "perf::PAGE-FAULTS").total);
}

TEST(Papi, CountsSumOverRegions) {
  SKIP_WITHOUT_PAPI();
  const SceneSpec spec = test::small_clustered(5000);
  const Scene scene = generate_scene(spec);
  PapiCounters counters(kSoftware);
  if (!counters.available()) GTEST_SKIP() << counters.record().reason;
  ContactDetector detector;
  DetectOptions options{parse_variant("cell/unsorted/dynamic,4"), spec.diameter, 2, &counters};
  detector.run(scene, options);
  detector.run(scene, options);
  const CounterRecord r = counters.record();
  EXPECT_EQ(r.counted_runs, 2);
  EXPECT_EQ(event(r, "perf::TASK-CLOCK").per_thread.size(), 2u);
}

TEST(Papi, UnknownEventNameIsAnInputError) {
  SKIP_WITHOUT_PAPI();
  try {
    PapiCounters counters({"PAPI_NOT_AN_EVENT_XYZ"});
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("unknown PAPI event 'PAPI_NOT_AN_EVENT_XYZ'"),
              std::string::npos);
  }
  EXPECT_THROW(PapiCounters({"perf::NO-SUCH-EVENT"}), InputError);
}

// The cache-miss formulas: counted with a rate where the machine has the events, otherwise a
// recorded reason. Never silent zeros.
TEST(Papi, CacheMissRatesOrAReason) {
  const SceneSpec spec = test::small_clustered(5000);
  const Scene scene = generate_scene(spec);
  PapiCounters counters;
  ContactDetector detector;
  DetectOptions options{parse_variant("particle/unsorted/static"), spec.diameter, 2, &counters};
  detector.run(scene, options);
  const CounterRecord r = counters.record();
  EXPECT_EQ(r.source, "papi");
  if (r.available) {
    EXPECT_TRUE(r.l1_miss_percent.has_value() || r.l2_miss_percent.has_value());
    if (r.l1_miss_percent) {
      EXPECT_FALSE(r.l1_formula.empty());
    }
  } else {
    EXPECT_FALSE(r.reason.empty());
    EXPECT_FALSE(r.l1_miss_percent.has_value());
    EXPECT_TRUE(r.events.empty());
  }
}

TEST(Papi, KnownButUncountableEventIsRecorded) {
  SKIP_WITHOUT_PAPI();
  for (const auto& probe : papi_info().cache_events) {
    if (probe.usable) continue;
    PapiCounters counters({probe.name});
    EXPECT_FALSE(counters.available());
    const CounterRecord r = counters.record();
    EXPECT_FALSE(r.available);
    EXPECT_NE(r.reason.find(probe.name), std::string::npos) << r.reason;
    return;
  }
  GTEST_SKIP() << "every cache event is countable on this machine";
}

TEST(Papi, MeasureDetectionKeepsCountersOutOfTheTimedRuns) {
  const SceneSpec spec = test::small_clustered(3000);
  const Scene scene = generate_scene(spec);
  PapiCounters counters(papi_info().initialized ? kSoftware : std::vector<std::string>{});
  MeasureOptions measure;
  measure.repetition.warmup = 0;
  measure.repetition.repeat = 3;
  measure.papi = &counters;
  ContactDetector detector;
  DetectOptions options{parse_variant("particle/sorted/static,64"), spec.diameter, 2, nullptr};
  const RunRecord run =
      measure_detection(detector, scene, describe_generated_scene(spec, scene), options, measure);
  ASSERT_EQ(run.counters.size(), 1u);
  EXPECT_EQ(run.counters[0].source, "papi");
  if (run.counters[0].available) {
    EXPECT_EQ(run.counters[0].counted_runs, 1);
  }
  EXPECT_EQ(run.samples.total_s.size(), 3u);
}

}  // namespace
}  // namespace contactlab::tuner
