// ThreadCounters' per-thread logic over the scripted backend, on every machine: each thread of
// the region counted once, exact per-thread values, sums and rates, formula fallbacks in order,
// failures reported with their thread, step and reason, and never a number that was not counted.
#include <fmt/core.h>
#include <gtest/gtest.h>
#include <omp.h>

#include <set>

#include "contactlab/kernels/error.hpp"
#include "contactlab/tuner/measure.hpp"
#include "contactlab/tuner/thread_counters.hpp"
#include "fake_counter_backend.hpp"
#include "program_test_support.hpp"

namespace contactlab::tuner {
namespace {

using test::FakeCounterBackend;
using test::FakeScript;

const std::vector<std::string> kEveryFormulaEvent{
    "PAPI_L1_DCM",          "PAPI_LST_INS", "PAPI_LD_INS",
    "PAPI_SR_INS",          "PAPI_L1_DCA",  "PAPI_L2_DCM",
    "PAPI_L2_TCM",          "PAPI_L2_DCA",  "perf::L1-DCACHE-LOAD-MISSES",
    "perf::L1-DCACHE-LOADS"};

// The counters over a scripted backend, keeping a view of the backend for the checks.
struct Counted {
  explicit Counted(FakeScript script, std::vector<std::string> events = {}) {
    auto owned = std::make_unique<FakeCounterBackend>(std::move(script));
    fake = owned.get();
    counters = std::make_unique<ThreadCounters>(std::move(owned), std::move(events));
  }
  FakeCounterBackend* fake = nullptr;
  std::unique_ptr<ThreadCounters> counters;
};

// One region through the observer hooks, the way the detector calls them. Returns how many
// threads OpenMP gave the region.
int run_region(ThreadCounters& counters, int threads) {
  int team = 0;
  counters.region_begin(threads);
#pragma omp parallel num_threads(threads)
  {
    const int t = omp_get_thread_num();
#pragma omp single
    team = omp_get_num_threads();
    counters.thread_begin(t);
    counters.thread_end(t);
  }
  counters.region_end();
  return team;
}

// One detection by the real detector with `counters` as its observer.
void run_detection(ThreadCounters& counters, int threads) {
  const SceneSpec spec = test::small_clustered(2000);
  const Scene scene = generate_scene(spec);
  ContactDetector detector;
  DetectOptions options{parse_variant("particle/sorted/dynamic,16"), spec.diameter, threads,
                        &counters};
  detector.run(scene, options);
}

const EventCount& event(const CounterRecord& r, const std::string& name) {
  for (const auto& e : r.events) {
    if (e.name == name) return e;
  }
  throw std::runtime_error("no event " + name);
}

FakeScript all_countable() {
  FakeScript s;
  s.known = kEveryFormulaEvent;
  s.countable = kEveryFormulaEvent;
  return s;
}

FakeScript software_events() {
  FakeScript s;
  s.known = {"soft::CLOCK", "soft::FAULTS", "soft::ABSENT"};
  s.countable = {"soft::CLOCK", "soft::FAULTS"};
  return s;
}

class ThreadCountersAt : public ::testing::TestWithParam<int> {};

TEST_P(ThreadCountersAt, TheDetectorCountsEveryThreadOnce) {
  const int threads = GetParam();
  const FakeScript script = software_events();
  Counted c(script, {"soft::CLOCK", "soft::FAULTS"});
  ASSERT_TRUE(c.counters->available());
  run_detection(*c.counters, threads);

  ASSERT_EQ(c.fake->regions.size(), 1u);
  const auto& log = c.fake->regions[0];
  EXPECT_EQ(log.events, (std::vector<std::string>{"soft::CLOCK", "soft::FAULTS"}));
  std::set<std::thread::id> os_threads;
  for (int t = 0; t < threads; ++t) {
    EXPECT_EQ(log.starts[t], 1) << "thread " << t;
    EXPECT_EQ(log.stops[t], 1) << "thread " << t;
    EXPECT_EQ(log.start_thread[t], log.stop_thread[t]) << "thread " << t << " moved";
    os_threads.insert(log.start_thread[t]);
  }
  EXPECT_EQ(os_threads.size(), static_cast<std::size_t>(threads))
      << "the per-thread calls did not run on distinct threads of the region";

  const CounterRecord r = c.counters->record();
  ASSERT_TRUE(r.available) << r.reason;
  EXPECT_EQ(r.source, "fake");
  EXPECT_EQ(r.counted_runs, 1);
  for (const std::string name : {"soft::CLOCK", "soft::FAULTS"}) {
    const EventCount& e = event(r, name);
    ASSERT_EQ(e.per_thread.size(), static_cast<std::size_t>(threads));
    std::uint64_t sum = 0;
    for (int t = 0; t < threads; ++t) {
      const auto expected = static_cast<std::uint64_t>(script.value(t, name, 0));
      EXPECT_EQ(e.per_thread[t], expected) << name << " thread " << t;
      sum += expected;
    }
    EXPECT_EQ(e.total, sum) << name;
  }
  EXPECT_FALSE(r.l1_miss_percent.has_value());  // no formula among the events: no rate
  EXPECT_FALSE(r.l2_miss_percent.has_value());
}

TEST_P(ThreadCountersAt, CountsSumOverRegions) {
  const int threads = GetParam();
  const FakeScript script = software_events();
  Counted c(script, {"soft::CLOCK"});
  for (int region = 0; region < 3; ++region) {
    ASSERT_EQ(run_region(*c.counters, threads), threads);
  }
  const CounterRecord r = c.counters->record();
  ASSERT_TRUE(r.available) << r.reason;
  EXPECT_EQ(r.counted_runs, 3);
  ASSERT_EQ(c.fake->regions.size(), 3u);
  const EventCount& e = event(r, "soft::CLOCK");
  ASSERT_EQ(e.per_thread.size(), static_cast<std::size_t>(threads));
  std::uint64_t total = 0;
  for (int t = 0; t < threads; ++t) {
    std::uint64_t expected = 0;
    for (int region = 0; region < 3; ++region) {
      EXPECT_EQ(c.fake->regions[region].starts[t], 1);
      EXPECT_EQ(c.fake->regions[region].stops[t], 1);
      expected += static_cast<std::uint64_t>(script.value(t, "soft::CLOCK", region));
    }
    EXPECT_EQ(e.per_thread[t], expected) << "thread " << t;
    total += expected;
  }
  EXPECT_EQ(e.total, total);
}

TEST_P(ThreadCountersAt, RatesAreExactFromKnownCounts) {
  const int threads = GetParam();
  FakeScript script = all_countable();
  // Per thread t: 5(t+1) L1 misses, 2(t+1) L2 misses, 100(t+1) loads and stores: 5 % and 2 %.
  script.value = [](int t, const std::string& e, int) -> long long {
    if (e == "PAPI_L1_DCM") return 5LL * (t + 1);
    if (e == "PAPI_L2_DCM") return 2LL * (t + 1);
    if (e == "PAPI_LST_INS") return 100LL * (t + 1);
    return 0;
  };
  Counted c(script);
  EXPECT_EQ(c.counters->event_names(),
            (std::vector<std::string>{"PAPI_L1_DCM", "PAPI_LST_INS", "PAPI_L2_DCM"}));
  run_detection(*c.counters, threads);
  const CounterRecord r = c.counters->record();
  ASSERT_TRUE(r.available) << r.reason;
  ASSERT_TRUE(r.l1_miss_percent.has_value());
  ASSERT_TRUE(r.l2_miss_percent.has_value());
  EXPECT_DOUBLE_EQ(*r.l1_miss_percent, 5.0);
  EXPECT_DOUBLE_EQ(*r.l2_miss_percent, 2.0);
  EXPECT_EQ(r.l1_formula, "100 * PAPI_L1_DCM / PAPI_LST_INS (per load/store instructions)");
  EXPECT_EQ(r.l2_formula, "100 * PAPI_L2_DCM / PAPI_LST_INS (per load/store instructions)");
  const int tt = threads * (threads + 1) / 2;  // sum of t+1
  EXPECT_EQ(event(r, "PAPI_LST_INS").total, static_cast<std::uint64_t>(100 * tt));
  EXPECT_TRUE(r.notes.empty());
}

TEST_P(ThreadCountersAt, StartFailureOnOneThreadIsReportedWithoutNumbers) {
  const int threads = GetParam();
  FakeScript script = software_events();
  script.fail_start_thread = threads - 1;
  Counted c(script, {"soft::CLOCK"});
  run_region(*c.counters, threads);
  const auto& log = c.fake->regions[0];
  for (int t = 0; t < threads; ++t) {
    EXPECT_EQ(log.starts[t], 1);
    // Stopped exactly where started: the failed thread released its set inside start.
    EXPECT_EQ(log.stops[t], t == threads - 1 ? 0 : 1) << "thread " << t;
  }
  const CounterRecord r = c.counters->record();
  EXPECT_FALSE(r.available);
  EXPECT_EQ(r.reason, fmt::format("thread {}: start: scripted start failure", threads - 1));
  EXPECT_TRUE(r.events.empty()) << "counts of the other threads were reported";
  EXPECT_EQ(r.counted_runs, 0);
  EXPECT_FALSE(r.l1_miss_percent.has_value());

  // Once failed, later regions are not counted and the reason stays.
  run_region(*c.counters, threads);
  EXPECT_EQ(c.fake->regions.size(), 1u);
  EXPECT_EQ(c.counters->record().reason, r.reason);
}

TEST_P(ThreadCountersAt, StopFailureAfterACountedRegionDiscardsEveryNumber) {
  const int threads = GetParam();
  FakeScript script = software_events();
  Counted counted_first(script, {"soft::CLOCK"});
  run_region(*counted_first.counters, threads);
  ASSERT_TRUE(counted_first.counters->record().available);

  script.fail_stop_thread = 0;
  Counted c(script, {"soft::CLOCK"});
  run_region(*c.counters, threads);
  const CounterRecord r = c.counters->record();
  EXPECT_FALSE(r.available);
  EXPECT_EQ(r.reason, "thread 0: stop: scripted stop failure");
  EXPECT_TRUE(r.events.empty());
}

INSTANTIATE_TEST_SUITE_P(Threads, ThreadCountersAt, ::testing::Values(1, 2, 3),
                         [](const auto& p) { return fmt::format("t{}", p.param); });

TEST(ThreadCounters, L1FallsBackToLoadsPlusStoresWithoutLstIns) {
  FakeScript script = all_countable();
  script.countable.erase(
      std::find(script.countable.begin(), script.countable.end(), "PAPI_LST_INS"));
  script.value = [](int, const std::string& e, int) -> long long {
    if (e == "PAPI_L1_DCM") return 30;
    if (e == "PAPI_L2_DCM") return 6;
    if (e == "PAPI_LD_INS") return 200;
    if (e == "PAPI_SR_INS") return 100;
    return 0;
  };
  Counted c(script);
  EXPECT_EQ(c.counters->event_names(),
            (std::vector<std::string>{"PAPI_L1_DCM", "PAPI_LD_INS", "PAPI_SR_INS", "PAPI_L2_DCM"}));
  run_region(*c.counters, 2);
  const CounterRecord r = c.counters->record();
  ASSERT_TRUE(r.available) << r.reason;
  EXPECT_EQ(r.l1_formula,
            "100 * PAPI_L1_DCM / (PAPI_LD_INS + PAPI_SR_INS) (per load/store instructions)");
  EXPECT_EQ(r.l2_formula,
            "100 * PAPI_L2_DCM / (PAPI_LD_INS + PAPI_SR_INS) (per load/store instructions)");
  EXPECT_DOUBLE_EQ(*r.l1_miss_percent, 10.0);  // 100 * 60 / 600
  EXPECT_DOUBLE_EQ(*r.l2_miss_percent, 2.0);   // 100 * 12 / 600
}

TEST(ThreadCounters, LaterCandidatesInOrderWhenEarlierOnesAreNotCountable) {
  FakeScript script;
  script.known = kEveryFormulaEvent;
  script.countable = {"PAPI_L1_DCM",
                      "PAPI_L1_DCA",
                      "PAPI_L2_DCM",
                      "PAPI_L2_DCA",
                      "perf::L1-DCACHE-LOAD-MISSES",
                      "perf::L1-DCACHE-LOADS"};
  Counted c(script);
  // L1: the third candidate (accesses), not the fourth (also countable); L2: the fourth.
  EXPECT_EQ(c.counters->event_names(),
            (std::vector<std::string>{"PAPI_L1_DCM", "PAPI_L1_DCA", "PAPI_L2_DCM", "PAPI_L2_DCA"}));
  run_region(*c.counters, 1);
  const CounterRecord r = c.counters->record();
  ASSERT_TRUE(r.available) << r.reason;
  EXPECT_EQ(r.l1_formula, "100 * PAPI_L1_DCM / PAPI_L1_DCA (per accesses)");
  EXPECT_EQ(r.l2_formula,
            "100 * PAPI_L2_DCM / PAPI_L2_DCA (per L2 data accesses (local miss rate))");
}

TEST(ThreadCounters, BothLevelsMustFitInOneSet) {
  FakeScript script = all_countable();
  script.max_events = 2;  // L1's two events fill the set: no L2 candidate fits beside them
  Counted c(script);
  EXPECT_EQ(c.counters->event_names(), (std::vector<std::string>{"PAPI_L1_DCM", "PAPI_LST_INS"}));
  run_region(*c.counters, 2);
  const CounterRecord r = c.counters->record();
  ASSERT_TRUE(r.available) << r.reason;
  EXPECT_TRUE(r.l1_miss_percent.has_value());
  EXPECT_FALSE(r.l2_miss_percent.has_value());
  EXPECT_TRUE(r.l2_formula.empty());
  EXPECT_EQ(r.notes, (std::vector<std::string>{"no L2 formula can be counted here"}));
}

TEST(ThreadCounters, NoCountableFormulaIsAReasonAndNoCounting) {
  FakeScript script;
  script.known = kEveryFormulaEvent;
  Counted c(script);
  EXPECT_FALSE(c.counters->available());
  run_region(*c.counters, 2);
  EXPECT_TRUE(c.fake->regions.empty()) << "a region was counted without events";
  const CounterRecord r = c.counters->record();
  EXPECT_FALSE(r.available);
  EXPECT_EQ(r.reason.rfind("no L1 or L2 data-cache miss formula can be counted here: "
                           "100 * PAPI_L1_DCM / PAPI_LST_INS (PAPI_L1_DCM: not countable here "
                           "(scripted)); ",
                           0),
            0u)
      << r.reason;
  EXPECT_TRUE(r.events.empty());
}

TEST(ThreadCounters, NoRateWhenTheDenominatorIsZero) {
  FakeScript script = all_countable();
  script.value = [](int, const std::string& e, int) -> long long {
    return e == "PAPI_L1_DCM" ? 7 : 0;
  };
  Counted c(script);
  run_region(*c.counters, 3);
  const CounterRecord r = c.counters->record();
  ASSERT_TRUE(r.available) << r.reason;
  EXPECT_FALSE(r.l1_miss_percent.has_value());
  EXPECT_FALSE(r.l2_miss_percent.has_value());
  EXPECT_TRUE(r.l1_formula.empty());
  EXPECT_EQ(event(r, "PAPI_L1_DCM").total, 21u);  // the counts themselves stay
  ASSERT_EQ(r.notes.size(), 2u);
  EXPECT_EQ(r.notes[0],
            "no L1 rate: the denominator of 100 * PAPI_L1_DCM / PAPI_LST_INS counted 0");
}

TEST(ThreadCounters, RequestedEventsFormingAFormulaGetItsRate) {
  FakeScript script = all_countable();
  script.value = [](int t, const std::string& e, int) -> long long {
    if (e == "PAPI_L1_DCM") return 1 + t;
    if (e == "PAPI_LD_INS") return 3 + 3 * t;
    if (e == "PAPI_SR_INS") return 1 + t;
    return 0;
  };
  Counted c(script, {"PAPI_L1_DCM", "PAPI_LD_INS", "PAPI_SR_INS"});
  run_region(*c.counters, 2);
  const CounterRecord r = c.counters->record();
  ASSERT_TRUE(r.available) << r.reason;
  EXPECT_DOUBLE_EQ(*r.l1_miss_percent, 25.0);  // 100 * 3 / (9 + 3)
  EXPECT_FALSE(r.l2_miss_percent.has_value());
}

TEST(ThreadCounters, UncountableRequestedEventIsRecordedWithItsReason) {
  Counted c(software_events(), {"soft::CLOCK", "soft::ABSENT"});
  EXPECT_FALSE(c.counters->available());
  run_region(*c.counters, 2);
  EXPECT_TRUE(c.fake->regions.empty());
  const CounterRecord r = c.counters->record();
  EXPECT_FALSE(r.available);
  EXPECT_EQ(r.reason,
            "cannot count the requested events here: soft::ABSENT: not countable here (scripted)");
  EXPECT_TRUE(r.events.empty());
}

TEST(ThreadCounters, UnknownEventIsAnInputError) {
  try {
    Counted c(software_events(), {"soft::CLOCK", "soft::TYPO"});
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "unknown fake event 'soft::TYPO'");
  }
}

TEST(ThreadCounters, MissingFacilityRecordsItsReasonAndAsksNothingElse) {
  FakeScript script = all_countable();
  script.unavailable = "scripted: no facility";
  Counted c(script, {"not even checked"});
  EXPECT_FALSE(c.counters->available());
  run_region(*c.counters, 2);
  EXPECT_EQ(c.fake->tries, 0);
  EXPECT_TRUE(c.fake->regions.empty());
  EXPECT_EQ(c.counters->record().reason, "scripted: no facility");
}

TEST(ThreadCounters, MeasureDetectionCountsOneExtraUntimedRun) {
  Counted c(software_events(), {"soft::CLOCK"});
  const SceneSpec spec = test::small_clustered(2000);
  const Scene scene = generate_scene(spec);
  MeasureOptions measure;
  measure.repetition.warmup = 1;
  measure.repetition.repeat = 3;
  measure.papi = c.counters.get();
  ContactDetector detector;
  DetectOptions options{parse_variant("particle/sorted/static,64"), spec.diameter, 2, nullptr};
  const RunRecord run =
      measure_detection(detector, scene, describe_generated_scene(spec, scene), options, measure);
  EXPECT_EQ(run.samples.total_s.size(), 3u);
  EXPECT_EQ(c.fake->regions.size(), 1u) << "the counters observed a timed run";
  ASSERT_EQ(run.counters.size(), 1u);
  EXPECT_TRUE(run.counters[0].available) << run.counters[0].reason;
  EXPECT_EQ(run.counters[0].counted_runs, 1);
  EXPECT_EQ(event(run.counters[0], "soft::CLOCK").per_thread.size(), 2u);
}

}  // namespace
}  // namespace contactlab::tuner
