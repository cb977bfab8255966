// The real PAPI backend, proved with software events that exist even where the machine
// exposes no hardware counters (virtual machines): perf::TASK-CLOCK and perf::PAGE-FAULTS.
// Where PAPI cannot count them (no PAPI, perf_event component disabled), these tests skip with
// the reason papi_probe gets from PAPI, decided before the test runs, never from its own result;
// once PAPI says the events are countable, the record must be available. The per-thread logic
// itself is tested on every machine in thread_counters_gtest.cpp.
#include <gtest/gtest.h>

#include "contactlab/kernels/error.hpp"
#include "contactlab/tuner/measure.hpp"
#include "contactlab/tuner/papi_counters.hpp"
#include "program_test_support.hpp"

namespace contactlab::tuner {
namespace {

const std::vector<std::string> kSoftware{"perf::TASK-CLOCK", "perf::PAGE-FAULTS"};

// Why PAPI cannot count the software events here, or "" when it can.
std::string software_events_obstacle() { return papi_probe(kSoftware).reason; }

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
  if (const auto why = software_events_obstacle(); !why.empty()) GTEST_SKIP() << why;
  const CounterRecord r = count_detection(20000, 2);
  ASSERT_TRUE(r.available) << r.reason;
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
  if (const auto why = software_events_obstacle(); !why.empty()) GTEST_SKIP() << why;
  const CounterRecord small = count_detection(2000, 2);
  ASSERT_TRUE(small.available) << small.reason;
  const CounterRecord large = count_detection(200000, 2);
  ASSERT_TRUE(large.available) << large.reason;
  EXPECT_GT(event(large, "perf::PAGE-FAULTS").total, event(small, "perf::PAGE-FAULTS").total);
}

TEST(Papi, CountsSumOverRegions) {
  if (const auto why = software_events_obstacle(); !why.empty()) GTEST_SKIP() << why;
  const SceneSpec spec = test::small_clustered(5000);
  const Scene scene = generate_scene(spec);
  PapiCounters counters(kSoftware);
  ASSERT_TRUE(counters.available()) << counters.record().reason;
  ContactDetector detector;
  DetectOptions options{parse_variant("cell/unsorted/dynamic,4"), spec.diameter, 2, &counters};
  detector.run(scene, options);
  detector.run(scene, options);
  const CounterRecord r = counters.record();
  ASSERT_TRUE(r.available) << r.reason;
  EXPECT_EQ(r.counted_runs, 2);
  const EventCount& clock = event(r, "perf::TASK-CLOCK");
  ASSERT_EQ(clock.per_thread.size(), 2u);
  EXPECT_EQ(clock.per_thread[0] + clock.per_thread[1], clock.total);
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
}

TEST(Papi, UnknownNativeEventIsAnInputError) {
  SKIP_WITHOUT_PAPI();
  if (const auto why = papi_disabled_component("perf::NO-SUCH-EVENT"); !why.empty()) {
    GTEST_SKIP() << "a typo cannot be told from an event of a disabled component: " << why;
  }
  EXPECT_THROW(PapiCounters({"perf::NO-SUCH-EVENT"}), InputError);
}

// On machines where PAPI disables perf_event (no PMU), its events cannot even be listed: they
// are recorded unavailable with PAPI's reason, not rejected as typos.
TEST(Papi, EventOfADisabledComponentIsRecordedWithPapisReason) {
  SKIP_WITHOUT_PAPI();
  const std::string why = papi_disabled_component("perf::TASK-CLOCK");
  if (why.empty()) GTEST_SKIP() << "PAPI's component of perf::TASK-CLOCK is enabled here";
  EXPECT_EQ(why.rfind("PAPI component perf_event is disabled: ", 0), 0u) << why;
  PapiCounters counters({"perf::TASK-CLOCK"});
  EXPECT_FALSE(counters.available());
  const CounterRecord r = counters.record();
  EXPECT_FALSE(r.available);
  EXPECT_EQ(r.reason, "cannot count the requested events here: perf::TASK-CLOCK: " + why);
  EXPECT_FALSE(papi_probe({"perf::TASK-CLOCK"}).countable);
}

// The cache-miss formulas: counted with a rate where PAPI says the machine has the events,
// otherwise a recorded reason. Never silent zeros.
TEST(Papi, CacheMissRatesOrAReason) {
  const bool countable = test::papi_counts_a_miss_formula();
  const SceneSpec spec = test::small_clustered(5000);
  const Scene scene = generate_scene(spec);
  PapiCounters counters;
  ContactDetector detector;
  DetectOptions options{parse_variant("particle/unsorted/static"), spec.diameter, 2, &counters};
  detector.run(scene, options);
  const CounterRecord r = counters.record();
  EXPECT_EQ(r.source, "papi");
  ASSERT_EQ(r.available, countable) << r.reason;
  if (countable) {
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
  if (const auto why = software_events_obstacle(); !why.empty()) GTEST_SKIP() << why;
  const SceneSpec spec = test::small_clustered(3000);
  const Scene scene = generate_scene(spec);
  PapiCounters counters(kSoftware);
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
  ASSERT_TRUE(run.counters[0].available) << run.counters[0].reason;
  EXPECT_EQ(run.counters[0].counted_runs, 1);
  EXPECT_EQ(run.samples.total_s.size(), 3u);
}

}  // namespace
}  // namespace contactlab::tuner
