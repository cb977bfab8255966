// contactlab tune end to end: the tuner reports every method honestly, --variant auto caches,
// --threads 0 means the same in tune and detect, --json's folders are made.
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "contactlab/tuner/tune_report.hpp"
#include "program_test_support.hpp"

namespace contactlab::test {
namespace {

using nlohmann::json;

// One cache for the tune tests (each runs in its own process): the CTest fixture
// tune_calibration (tests/tuner/CMakeLists.txt) calibrates the machine into it before them, and
// they find the calibration (keyed by machine and build) there.
std::string tune_cache() { return CONTACTLAB_TUNE_CACHE_DIR; }

// A fresh cache holding the shared calibration and no tuned choice, for the tests whose first
// step must miss.
std::string cache_without_choices(const std::string& name) {
  std::string dir = temp_dir(name);
  json cache = json::parse(std::ifstream(tune_cache() + "/tuning.json"));
  cache["choices"] = json::object();
  std::ofstream(dir + "/tuning.json") << cache.dump();
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

// The calibration stores the half stencil's exchange (output_cost.hpp) at its multi-thread
// point, from a dynamic deal's assembly against the block's, and none where nothing is passed
// on: one thread, the full stencil.
TEST(TuneCli, TheCalibrationHoldsTheHalfStencilsExchange) {
  const json cache = json::parse(std::ifstream(tune_cache() + "/tuning.json"));
  bool half_at_two = false;
  for (const auto& [machine, calibration] : cache["calibrations"].items()) {
    if (calibration["cost_model_version"] != 6) continue;  // older entries are misses
    for (const auto& [structure, costs] : calibration["structures"].items()) {
      for (const json& point : costs["output"]) {
        ASSERT_TRUE(point.contains("exchange")) << structure << point;
        const double exchange = point["exchange"].get<double>();
        EXPECT_GE(exchange, 0.0) << structure << point;
        const bool half = structure.find("/half") != std::string::npos;
        if (!half || point["threads"] == 1) {
          EXPECT_EQ(exchange, 0.0) << structure << point;
        }
        half_at_two = half_at_two || (half && point["threads"] == 2);
      }
    }
  }
  if (omp_get_num_procs() >= 2) {
    EXPECT_TRUE(half_at_two) << "no half stencil calibrated at 2";
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
  // The model's best schedule of every structure it priced is verified too, and the fastest
  // verified choice is among everything verified: no regret below zero, and one of zero.
  double smallest_regret = 1e9;
  for (const auto& s : t["methods"][0]["structures"]) {
    ASSERT_TRUE(s.contains("regret")) << s.dump();
    EXPECT_GT(s["measured"]["median_s"].get<double>(), 0.0);
    EXPECT_GE(s["regret"].get<double>(), 0.0);
    smallest_regret = std::min(smallest_regret, s["regret"].get<double>());
  }
  for (const auto& m : t["methods"])
    smallest_regret = std::min(smallest_regret, m["regret"].get<double>());
  for (const auto& c : t["classic"])
    smallest_regret = std::min(smallest_regret, c["regret"].get<double>());
  EXPECT_EQ(smallest_regret, 0.0);
  // With a static schedule the sweep measures the block (chunk 0) too, as the search may choose
  // it: the exhaustive best is then never beaten by a choice off its grid.
  const auto& swept = t["methods"][2]["chunks_measured"];
  const bool static_kind =
      t["methods"][1]["variant"].get<std::string>().find("/static") != std::string::npos;
  EXPECT_EQ(swept.back()["chunk"].get<int>() == 0, static_kind) << t["methods"][2].dump();
  // The search spends fewer timed runs than the exhaustive sweep.
  EXPECT_LT(t["methods"][1]["evaluations"].get<int>() * 3,
            t["methods"][2]["timed_runs"].get<int>());
  EXPECT_TRUE(t["context"].contains("machine"));
  // The strict reader takes what tune wrote, and finds each method by name.
  const tuner::TuneDocument typed = tuner::read_tune_document(dir + "/t.json");
  ASSERT_NE(typed.method("exhaustive"), nullptr);
  EXPECT_TRUE(typed.method("search")->regret.has_value());
  EXPECT_EQ(typed.classic.size(), t["classic"].size());
}

TEST(TuneCli, VariantAutoTunesOnAMissThenUsesTheCache) {
  const std::string scene = " --scene uniform --n 5000 -D 0.03 --threads 2";
  const std::string env = "CONTACTLAB_CACHE_DIR=" + cache_without_choices("auto_cache") + " ";
  const auto first =
      run_command(env + contactlab_exe() + " detect" + scene + " --variant auto --repeat 1");
  ASSERT_EQ(first.exit_code, 0) << first.output;
  EXPECT_NE(first.output.find("tuning"), std::string::npos) << first.output;
  const auto second =
      run_command(env + contactlab_exe() + " detect" + scene + " --variant auto --repeat 1");
  ASSERT_EQ(second.exit_code, 0) << second.output;
  EXPECT_NE(second.output.find("(from "), std::string::npos) << second.output;
}

// --threads 0 means OpenMP's default team size in tune and in detect alike, so a choice that
// tune stored under OMP_NUM_THREADS=1 is the one --variant auto finds.
TEST(TuneCli, ThreadsZeroFollowsOmpNumThreadsInTuneAndVariantAuto) {
  const std::string dir = temp_dir("tune_threads0");
  const std::string env =
      "OMP_NUM_THREADS=1 CONTACTLAB_CACHE_DIR=" + cache_without_choices("threads0_cache") + " ";
  const std::string scene = " --scene uniform --n 4000 -D 0.04 --seed 11 --threads 0";
  const auto tuned = run_command(env + contactlab_exe() + " tune" + scene + " --max-chunk 64" +
                                 " --verify-rounds 3 --json " + dir + "/t.json");
  ASSERT_EQ(tuned.exit_code, 0) << tuned.output;
  EXPECT_EQ(json::parse(std::ifstream(dir + "/t.json"))["threads"], 1) << tuned.output;
  const auto detected =
      run_command(env + contactlab_exe() + " detect" + scene + " --variant auto --repeat 1");
  ASSERT_EQ(detected.exit_code, 0) << detected.output;
  EXPECT_NE(detected.output.find("(from "), std::string::npos)
      << "--variant auto missed the choice tune stored:\n"
      << detected.output;
  EXPECT_EQ(detected.output.find("no cached choice"), std::string::npos) << detected.output;
}

// Planning for a larger machine (`--threads 16 --predict-only` on a 2-core one) calibrates on the
// cores this machine has: timed oversubscribed, the threads took turns and the model priced 16
// threads slower than 8. A cached calibration timed on more threads than the cores (one written
// before this rule) is not used; the new one is, on the next run.
TEST(TuneCli, PlanningForMoreThreadsThanCoresCalibratesOnTheCores) {
  const int cores = omp_get_num_procs();
  const int planned = cores + 14;
  const std::string cache_dir = cache_without_choices("planned_cache");
  {
    json cache = json::parse(std::ifstream(cache_dir + "/tuning.json"));
    for (auto& [key, calibration] : cache["calibrations"].items()) calibration["threads"] = planned;
    std::ofstream(cache_dir + "/tuning.json") << cache.dump();
  }
  const std::string dir = temp_dir("tune_planned");
  const std::string tune = "CONTACTLAB_CACHE_DIR=" + cache_dir + " " + contactlab_exe() +
                           " tune --scene clustered --n 200000 -D 0.01 --threads " +
                           std::to_string(planned) + " --predict-only --json " + dir + "/t.json";
  const auto first = run_command(tune);
  ASSERT_EQ(first.exit_code, 0) << first.output;
  EXPECT_NE(first.output.find("calibrating"), std::string::npos)
      << "an oversubscribed calibration was used:\n"
      << first.output;
  const json cache = json::parse(std::ifstream(cache_dir + "/tuning.json"));
  // (Other builds' calibrations in a reused build folder's cache keep the planned count.)
  int on_the_cores = 0;
  for (const auto& [key, calibration] : cache["calibrations"].items())
    on_the_cores += calibration["threads"] == cores ? 1 : 0;
  EXPECT_EQ(on_the_cores, 1) << cache["calibrations"].dump();
  // With the calibration of this machine's cores, more threads are predicted faster, not slower.
  const json t = json::parse(std::ifstream(dir + "/t.json"));
  double previous = 0.0;
  for (const auto& p : t["predictions"]) {
    if (previous > 0.0) {
      EXPECT_LT(p["predicted_s"].get<double>(), previous) << p.dump();
    }
    previous = p["predicted_s"].get<double>();
  }
  const auto second = run_command(tune);
  ASSERT_EQ(second.exit_code, 0) << second.output;
  EXPECT_EQ(second.output.find("calibrating"), std::string::npos) << second.output;
}

// --json in folders that do not exist yet: made (as mkdir -p); under a file, one line before
// the tuning starts.
TEST(TuneCli, JsonMakesItsFolders) {
  const std::string dir = temp_dir("tune_folders");
  const std::string tune = "CONTACTLAB_CACHE_DIR=" + tune_cache() + " " + contactlab_exe() +
                           " tune --scene uniform --n 2000 -D 0.05 --threads 1 --predict-only"
                           " --json ";
  const auto r = run_command(tune + dir + "/new/a/b/t.json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(json::parse(std::ifstream(dir + "/new/a/b/t.json"))["methods"].size(), 1u);
  const std::string blocker = dir + "/blocker";
  expect_blocked(run_command(tune + path_under_a_file(blocker, "t.json")), blocker);
}

TEST(TuneCli, RoundsBelowOneAreAClearError) {
  for (const char* option : {"--verify-rounds", "--search-samples", "--exhaustive-rounds"}) {
    const auto r =
        run_command(contactlab_exe() + " tune --scene uniform --n 1000 -D 0.05 " + option + " 0");
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find(std::string("contactlab: error: ") + option + " must be >= 1"),
              std::string::npos)
        << r.output;
  }
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
