// contactlab sweep end to end: results are complete, an interrupted sweep resumes to the same
// set of points, a bad config writes nothing, --out's folders are made.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>

#include "contactlab/tuner/result_schema.hpp"
#include "program_test_support.hpp"

namespace contactlab::test {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

std::set<std::string> point_keys(const std::string& path) {
  const tuner::ResultFile result = tuner::read_result_file(path);
  std::set<std::string> keys;
  for (const auto& run : result.runs) {
    keys.insert(run.parameters.scene.checksum + "|" + run.parameters.variant + "|" +
                std::to_string(run.parameters.threads));
  }
  return keys;
}

const std::string kSmoke = std::string(CONTACTLAB_SOURCE_DIR) + "/experiments/smoke.json";

TEST(SweepCli, WritesEveryPointCheckedAgainstTheReference) {
  const std::string dir = temp_dir("sweep_full");
  const auto r = run_command(contactlab_exe() + " sweep " + kSmoke + " --out " + dir + "/r.json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const tuner::ResultFile result = tuner::read_result_file(dir + "/r.json");
  EXPECT_EQ(result.runs.size(), 20u);  // 2 scenes x (3 + 1 + 1) variants x 2 thread counts
  for (const auto& run : result.runs) {
    EXPECT_EQ(run.status, tuner::RunStatus::kOk) << run.message;
    ASSERT_TRUE(run.contact_check) << run.parameters.variant;
    if (run.parameters.variant.find("float") == std::string::npos) {
      EXPECT_EQ(run.contact_check->missing_pairs + run.contact_check->extra_pairs, 0u);
    }
  }
  // A second sweep into the same file is refused, and the file is untouched.
  const auto again =
      run_command(contactlab_exe() + " sweep " + kSmoke + " --out " + dir + "/r.json");
  EXPECT_EQ(again.exit_code, 2);
  EXPECT_NE(again.output.find("--resume"), std::string::npos);
  EXPECT_EQ(point_keys(dir + "/r.json").size(), 20u);
}

TEST(SweepCli, InterruptedSweepResumesToTheSameSetOfPoints) {
  const std::string dir = temp_dir("sweep_resume");
  // A slower config: interrupt it after a moment (wherever it is), then resume.
  json config = json::parse(std::ifstream(kSmoke));
  config["scenes"][0]["n"] = 60000;
  config["scenes"][0]["diameter"] = 0.01;
  config["repetitions"] = {{"warmup", 1}, {"min", 3}};
  std::ofstream(dir + "/slow.json") << config.dump();
  const std::string sweep =
      contactlab_exe() + " sweep " + dir + "/slow.json --out " + dir + "/r.json";
  run_command("timeout -s INT 1.5 " + sweep);
  if (fs::exists(dir + "/r.json")) {
    const auto partial = point_keys(dir + "/r.json");  // a valid file, whatever it holds
    EXPECT_LE(partial.size(), 20u);
  }
  const auto resumed = run_command(sweep + " --resume");
  ASSERT_EQ(resumed.exit_code, 0) << resumed.output;
  const auto full =
      run_command(contactlab_exe() + " sweep " + dir + "/slow.json --out " + dir + "/full.json");
  ASSERT_EQ(full.exit_code, 0) << full.output;
  EXPECT_EQ(point_keys(dir + "/r.json"), point_keys(dir + "/full.json"));
  EXPECT_EQ(point_keys(dir + "/r.json").size(), 20u);
}

// With rounds, every point holds one visit of `min` repetitions per round, each tagged with its
// round, and a sweep interrupted mid-round resumes to the same visits.
TEST(SweepCli, RoundsVisitEveryPointOncePerRoundAndResume) {
  const std::string dir = temp_dir("sweep_rounds");
  json config = json::parse(std::ifstream(kSmoke));
  config["repetitions"] = {{"warmup", 0}, {"min", 2}, {"rounds", 3}};
  std::ofstream(dir + "/rounds.json") << config.dump();
  const std::string sweep =
      contactlab_exe() + " sweep " + dir + "/rounds.json --out " + dir + "/r.json";
  run_command("timeout -s INT 1 " + sweep);
  const auto resumed = run_command(sweep + " --resume");
  ASSERT_EQ(resumed.exit_code, 0) << resumed.output;
  const tuner::ResultFile result = tuner::read_result_file(dir + "/r.json");
  ASSERT_EQ(result.runs.size(), 20u);
  for (const auto& run : result.runs) {
    EXPECT_EQ(run.status, tuner::RunStatus::kOk) << run.message;
    ASSERT_TRUE(run.samples.round) << run.parameters.variant;
    std::multiset<int> rounds(run.samples.round->begin(), run.samples.round->end());
    EXPECT_EQ(rounds, (std::multiset<int>{0, 0, 1, 1, 2, 2})) << run.parameters.variant;
    ASSERT_TRUE(run.aggregates);
    EXPECT_EQ(run.aggregates->repetitions, 6);
    EXPECT_EQ(run.samples.total_s.size(), 6u);
  }
  // Resuming a complete sweep measures nothing.
  const auto again = run_command(sweep + " --resume");
  ASSERT_EQ(again.exit_code, 0) << again.output;
  EXPECT_NE(again.output.find("20 already done"), std::string::npos) << again.output;
}

// A sweep resumes only on the machine and with the build its file names: the file's one context
// would otherwise label the points measured before, elsewhere or by other code, as this run's.
// A complete file resumes to nothing measured whatever made it (the study resumes its sweeps).
TEST(SweepCli, ResumesOnlyOnTheMachineAndBuildItsFileNames) {
  const std::string dir = temp_dir("sweep_origin");
  const std::string out = dir + "/r.json";
  const std::string sweep = contactlab_exe() + " sweep " + kSmoke + " --out " + out;
  const auto first = run_command(sweep);
  ASSERT_EQ(first.exit_code, 0) << first.output;
  json file = json::parse(std::ifstream(out));
  const json own_build = file["context"]["build"];
  const json own_machine = file["context"]["machine"];
  file["context"]["build"]["git_commit"] = "0123456789abcdef0123456789abcdef01234567";
  std::ofstream(out) << file.dump();
  const auto complete = run_command(sweep + " --resume");
  EXPECT_EQ(complete.exit_code, 0) << complete.output;
  EXPECT_NE(complete.output.find("20 already done"), std::string::npos) << complete.output;

  file["runs"].erase(file["runs"].begin());  // a point left to measure
  std::ofstream(out) << file.dump();
  const std::string before = slurp(out);
  const auto other_build = run_command(sweep + " --resume");
  EXPECT_EQ(other_build.exit_code, 2) << other_build.output;
  EXPECT_NE(other_build.output.find("measured by the build of commit 0123456789"),
            std::string::npos)
      << other_build.output;
  EXPECT_NE(other_build.output.find("same machine and build only"), std::string::npos);
  EXPECT_EQ(slurp(out), before);

  file["context"]["build"] = own_build;
  file["context"]["machine"]["cpu_model"] = "Another CPU";
  std::ofstream(out) << file.dump();
  const auto other_machine = run_command(sweep + " --resume");
  EXPECT_EQ(other_machine.exit_code, 2) << other_machine.output;
  EXPECT_NE(other_machine.output.find("measured on 'Another CPU'"), std::string::npos)
      << other_machine.output;

  file["context"]["machine"] = own_machine;  // its own machine and build: the point is measured
  std::ofstream(out) << file.dump();
  const auto own = run_command(sweep + " --resume");
  ASSERT_EQ(own.exit_code, 0) << own.output;
  EXPECT_EQ(point_keys(out).size(), 20u);
}

// --out in folders that do not exist yet: made (as mkdir -p); under a file, one line before
// any point is measured.
TEST(SweepCli, OutMakesItsFolders) {
  const std::string dir = temp_dir("sweep_folders");
  json config = json::parse(std::ifstream(kSmoke));
  config["scenes"] = json::array({config["scenes"][1]});
  config["variants"] = {"cell/unsorted/half/dynamic,4"};
  config["threads"] = {1};
  std::ofstream(dir + "/one.json") << config.dump();
  const std::string out = dir + "/new/a/b/r.json";
  const auto r = run_command(contactlab_exe() + " sweep " + dir + "/one.json --out " + out);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(point_keys(out).size(), 1u);
  const std::string blocker = dir + "/blocker";
  expect_blocked(run_command(contactlab_exe() + " sweep " + dir + "/one.json --out " +
                             path_under_a_file(blocker, "r.json")),
                 blocker);
}

TEST(SweepCli, BadConfigIsOneLineAndWritesNothing) {
  const std::string dir = temp_dir("sweep_bad");
  std::ofstream(dir + "/bad.json")
      << R"({"schema_version": 1, "name": "x", "scenes": [], "variants": [], "threads": [1]})";
  const auto r =
      run_command(contactlab_exe() + " sweep " + dir + "/bad.json --out " + dir + "/r.json");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("$.scenes: expected a non-empty array"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir + "/r.json"));
}

}  // namespace
}  // namespace contactlab::test
