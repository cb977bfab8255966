// contactlab detect end to end: the result file it writes passes the strict reader, with
// counters or a recorded reason; bad input gives one clear line, exit 2 and no file. Also the
// output folders of detect, scene and partition: made when missing (as mkdir -p), and a path
// that cannot be made is one line, exit 2, before any work and with the old output kept.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "contactlab/kernels/scene_options.hpp"
#include "contactlab/tuner/papi_counters.hpp"
#include "contactlab/tuner/result_schema.hpp"
#include "program_test_support.hpp"

namespace contactlab::tuner {
namespace {

const std::string kScene = " detect --scene clustered --n 3000 -D 0.02 --seed 3 ";

test::CommandResult detect(const std::string& options) {
  return test::run_command(test::contactlab_exe() + kScene + options);
}

TEST(DetectCli, PapiWritesCountersOrAReason) {
  const bool countable = test::papi_counts_a_miss_formula();  // asked of PAPI, not of the run
  test::TempDir dir;
  const std::string json = dir.file("r.json");
  const auto r = detect("--threads 2 --repeat 3 --papi --json " + json);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const ResultFile file = read_result_file(json);
  ASSERT_EQ(file.runs.size(), 1u);
  const RunRecord& run = file.runs[0];
  EXPECT_EQ(run.status, RunStatus::kOk);
  ASSERT_EQ(run.counters.size(), 1u);
  const CounterRecord& c = run.counters[0];
  EXPECT_EQ(c.source, "papi");
  ASSERT_EQ(c.available, countable) << c.reason;
  if (countable) {
    EXPECT_TRUE(c.l1_miss_percent || c.l2_miss_percent);
  } else {
    EXPECT_FALSE(c.reason.empty());
    EXPECT_NE(r.output.find("unavailable"), std::string::npos);
  }
  EXPECT_EQ(run.samples.total_s.size(), 3u);
  EXPECT_EQ(run.samples.thread_busy_s[0].size(), 2u);
  EXPECT_EQ(file.context.openmp.threads, 2);
  EXPECT_NE(file.context.command_line.find("--papi"), std::string::npos);
}

TEST(DetectCli, SoftwareEventsPerThread) {
  if (const auto why = papi_probe({"perf::TASK-CLOCK"}).reason; !why.empty()) GTEST_SKIP() << why;
  test::TempDir dir;
  const std::string json = dir.file("r.json");
  const auto r =
      detect("--threads 2 --repeat 1 --warmup 0 --papi-events perf::TASK-CLOCK --json " + json);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const CounterRecord c = read_result_file(json).runs[0].counters[0];
  ASSERT_TRUE(c.available) << c.reason;
  ASSERT_EQ(c.events.size(), 1u);
  EXPECT_EQ(c.events[0].per_thread.size(), 2u);
}

TEST(DetectCli, CacheSimulationFx10) {
  if (const auto why = test::valgrind_obstacle(); !why.empty()) GTEST_SKIP() << why;
  test::TempDir dir;
  const std::string json = dir.file("r.json");
  const auto r = detect(
      "--variant cell/unsorted/static --threads 1 --repeat 1 --warmup 0 --cache-sim fx10 --json " +
      json);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const CounterRecord c = read_result_file(json).runs[0].counters[0];
  EXPECT_EQ(c.source, "simulated:fx10");
  ASSERT_TRUE(c.available) << c.reason;
  EXPECT_TRUE(c.l1_miss_percent.has_value());
  EXPECT_TRUE(c.l2_miss_percent.has_value());
  ASSERT_TRUE(c.simulation.has_value());
  EXPECT_TRUE(c.simulation->geometry.approximation);
  // The simulated program is not the native binary: the result says what it was built for.
  EXPECT_FALSE(c.simulation->code_isa.empty());
  EXPECT_NE(c.simulation->executable.find("contactlab-cachesim"), std::string::npos);
}

TEST(DetectCli, MissingValgrindIsRecorded) {
  test::TempDir dir;
  const std::string json = dir.file("r.json");
  const auto r =
      test::run_command("CONTACTLAB_VALGRIND=/nonexistent/valgrind " + test::contactlab_exe() +
                        kScene + "--repeat 1 --cache-sim fx10 --json " + json);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const CounterRecord c = read_result_file(json).runs[0].counters[0];
  EXPECT_FALSE(c.available);
  EXPECT_NE(c.reason.find("/nonexistent/valgrind"), std::string::npos) << c.reason;
}

TEST(DetectCli, AdaptiveRepetition) {
  test::TempDir dir;
  const std::string json = dir.file("r.json");
  const auto r = detect(
      "--threads 1 --repeat 2 --adaptive --target-ci 0.5 --time-budget 10 --max-repeat 40 --json " +
      json);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const RunRecord run = read_result_file(json).runs[0];
  EXPECT_GE(run.aggregates->repetitions, 2);
  EXPECT_LE(run.aggregates->repetitions, 40);
  EXPECT_NE(run.aggregates->stop_reason, StopReason::kFixedCount);
  EXPECT_TRUE(run.parameters.repetition.adaptive);
}

TEST(DetectCli, ContactsOutStillWritten) {
  test::TempDir dir;
  const auto r = detect("--repeat 1 --contacts-out " + dir.file("c.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(std::filesystem::exists(dir.file("c.csv")));
}

TEST(DetectCli, JsonMakesItsFolders) {
  test::TempDir dir;
  const std::string json = dir.file("new/a/b/r.json");
  const auto r = detect("--repeat 1 --warmup 0 --json " + json);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(read_result_file(json).runs.size(), 1u);
}

TEST(DetectCli, ContactsOutMakesItsFolders) {
  test::TempDir dir;
  const std::string csv = dir.file("new/a/b/c.csv");
  const auto r = detect("--repeat 1 --warmup 0 --contacts-out " + csv);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(test::slurp(csv).rfind("i,j\n", 0), 0u);
}

// One output's folder cannot be made: the run stops before detecting, and the other output's
// earlier file is kept as it was.
TEST(DetectCli, AFileInTheWayIsOneLineAndKeepsTheOldOutput) {
  test::TempDir dir;
  const std::string json = dir.file("r.json");
  std::ofstream(json) << "earlier result\n";
  const std::string blocker = dir.file("blocker");
  const auto r = detect("--repeat 1 --json " + json + " --contacts-out " +
                        test::path_under_a_file(blocker, "c.csv"));
  test::expect_blocked(r, blocker);
  EXPECT_EQ(test::slurp(json), "earlier result\n");
  const auto other = detect("--repeat 1 --json " + test::path_under_a_file(blocker, "r.json"));
  test::expect_blocked(other, blocker);
}

TEST(SceneCli, OutMakesItsFolders) {
  test::TempDir dir;
  const std::string out = dir.file("new/a/b/s.csv");
  const auto r = test::run_command(test::contactlab_exe() +
                                   " scene --kind uniform --n 100 -D 0.05 --out " + out);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(std::filesystem::is_regular_file(out));
  const std::string blocker = dir.file("blocker");
  test::expect_blocked(
      test::run_command(test::contactlab_exe() + " scene --kind uniform --n 100 -D 0.05 --out " +
                        test::path_under_a_file(blocker, "s.bin")),
      blocker);
}

TEST(PartitionCli, JsonMakesItsFolders) {
  test::TempDir dir;
  const std::string json = dir.file("new/a/b/p.json");
  const auto r =
      test::run_command(test::contactlab_exe() +
                        " partition --scene uniform --n 1000 -D 0.05 --ranks 2 --json " + json);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(std::filesystem::is_regular_file(json));
  const std::string blocker = dir.file("blocker");
  test::expect_blocked(
      test::run_command(test::contactlab_exe() +
                        " partition --scene uniform --n 1000 -D 0.05 --ranks 2 --json " +
                        test::path_under_a_file(blocker, "p.json")),
      blocker);
}

void expect_rejected(const std::string& options, const std::string& message) {
  test::TempDir dir;
  const std::string json = dir.file("r.json");
  const auto r = detect(options + " --json " + json);
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("contactlab: error: "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(message), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("Run with --help"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(json)) << "a result file was written for bad input";
}

TEST(DetectCli, BadInputIsOneClearError) {
  expect_rejected("--cache-sim custom:48K,8,64:1M,16,64", "not a power of two");
  expect_rejected("--cache-sim sparc", "unknown cache geometry 'sparc'");
  expect_rejected("--adaptive --target-ci 2", "--target-ci");
  // Parse errors too: one line (CLI11's own exit added "Run with --help ..." and exit 105 - 109).
  expect_rejected("--no-such-option", "--no-such-option");
  expect_rejected("--repeat many", "many");
  // Numbers in messages as given, not as std::to_string's six decimals (0.000000).
  const auto tiny = test::run_command(test::contactlab_exe() +
                                      " detect --scene uniform --n 100 -D 1e-300 --repeat 1");
  EXPECT_EQ(tiny.exit_code, 2) << tiny.output;
  EXPECT_NE(tiny.output.find("D = 1e-300 is too small"), std::string::npos) << tiny.output;
  if (papi_info().initialized)
    expect_rejected("--papi-events PAPI_NOT_AN_EVENT_XYZ", "unknown PAPI event");
}

// The scene options come from the library's table (the one the experiment configs read).
TEST(DetectCli, SceneOptionsComeFromTheTable) {
  for (const char* command : {" scene --help", " detect --help", " tune --help", " demo --help"}) {
    const auto r = test::run_command(test::contactlab_exe() + command);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    for (const SceneParameter& parameter : kSceneParameters) {
      EXPECT_NE(r.output.find(std::string(parameter.option)), std::string::npos)
          << command << " lacks " << parameter.option;
    }
  }
}

}  // namespace
}  // namespace contactlab::tuner
