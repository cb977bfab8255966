// contactlab sweep and tune end to end: results are complete, an interrupted sweep resumes to
// the same set of points, the tuner reports every method honestly, --variant auto caches.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>

#include "contactlab/tuner/result_schema.hpp"
#include "tuner_test_support.hpp"

namespace contactlab::test {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

std::string temp_dir(const std::string& name) {
  const fs::path dir = fs::path(testing::TempDir()) / ("contactlab_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir.string();
}

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

// One cache for the tune tests (each runs in its own process): the machine is calibrated by
// the first and the others find the calibration (keyed by machine and build) in the cache.
const std::string& tune_cache() {
  static const std::string dir = [] {
    const fs::path path = fs::path(testing::TempDir()) / "contactlab_tune_cache";
    fs::create_directories(path);
    return path.string();
  }();
  return dir;
}

TEST(TuneCli, PredictOnlyMakesNoTimedRunAndLabelsPredictions) {
  const std::string dir = temp_dir("tune_predict");
  const auto r = run_command("CONTACTLAB_CACHE_DIR=" + tune_cache() + " " + contactlab_exe() +
                             " tune --scene clustered --n 20000 -D 0.01 --threads 2 --max-chunk 256"
                             " --predict-only --json " +
                             dir + "/t.json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const json t = json::parse(std::ifstream(dir + "/t.json"));
  ASSERT_EQ(t["methods"].size(), 1u);
  EXPECT_EQ(t["methods"][0]["method"], "model");
  EXPECT_EQ(t["methods"][0]["timed_runs"], 0);
  EXPECT_FALSE(t["classic"].empty());
  for (const auto& p : t["predictions"]) {
    EXPECT_NE(p["label"].get<std::string>().find("predicted"), std::string::npos);
  }
}

TEST(TuneCli, ReportsModelSearchExhaustiveWithRegretAndCost) {
  const std::string dir = temp_dir("tune_full");
  const auto r =
      run_command("CONTACTLAB_CACHE_DIR=" + tune_cache() + " " + contactlab_exe() +
                  " tune --scene blobs --blobs 1 --n 20000 -D 0.01 --threads 2 --max-chunk 256"
                  " --exhaustive --json " +
                  dir + "/t.json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const json t = json::parse(std::ifstream(dir + "/t.json"));
  ASSERT_EQ(t["methods"].size(), 3u);
  EXPECT_EQ(t["methods"][0]["method"], "model");
  EXPECT_EQ(t["methods"][1]["method"], "search");
  EXPECT_EQ(t["methods"][2]["method"], "exhaustive");
  for (int m = 0; m < 2; ++m) {
    EXPECT_GE(t["methods"][m]["regret"].get<double>(), 0.0);
    EXPECT_GT(t["methods"][m]["measured"]["median_s"].get<double>(), 0.0);
    EXPECT_GE(t["methods"][m]["tuning_cost_s"].get<double>(), 0.0);
  }
  // The search spends fewer timed runs than the exhaustive sweep.
  EXPECT_LT(t["methods"][1]["evaluations"].get<int>() * 3,
            t["methods"][2]["timed_runs"].get<int>());
  EXPECT_TRUE(t["context"].contains("machine"));
}

TEST(TuneCli, VariantAutoTunesOnAMissThenUsesTheCache) {
  const std::string scene = " --scene uniform --n 5000 -D 0.03 --threads 2";
  const std::string env = "CONTACTLAB_CACHE_DIR=" + tune_cache() + " ";
  const auto first =
      run_command(env + contactlab_exe() + " detect" + scene + " --variant auto --repeat 1");
  ASSERT_EQ(first.exit_code, 0) << first.output;
  EXPECT_NE(first.output.find("tuning"), std::string::npos) << first.output;
  const auto second =
      run_command(env + contactlab_exe() + " detect" + scene + " --variant auto --repeat 1");
  ASSERT_EQ(second.exit_code, 0) << second.output;
  EXPECT_NE(second.output.find("(from "), std::string::npos) << second.output;
}

TEST(TuneCli, CorruptCacheIsAClearError) {
  const std::string dir = temp_dir("tune_corrupt");
  std::ofstream(dir + "/tuning.json") << "{ broken";
  const auto r = run_command("CONTACTLAB_CACHE_DIR=" + dir + " " + contactlab_exe() +
                             " tune --scene uniform --n 1000 -D 0.05 --predict-only");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("tuning cache is not valid JSON"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace contactlab::test
