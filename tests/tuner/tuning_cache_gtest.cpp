// The tuning cache's file: what is stored reads back, with every cost constant; a calibration of
// another cost model is a miss; a file that does not follow the cache's records is an error that
// names the file and the JSON path.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "contactlab/kernels/error.hpp"
#include "contactlab/tuner/tune.hpp"
#include "program_test_support.hpp"

namespace contactlab::tuner {
namespace {

using nlohmann::json;

Calibration sample_calibration() {
  Calibration c;
  c.seconds = 12.5;
  c.threads = 2;
  MachineCosts costs;
  costs.seconds_per_test = 3e-9;
  costs.seconds_per_cold_test = 2e-8;
  costs.seconds_per_weighed_iteration = 9e-10;
  costs.seconds_per_weighed_build = 0.0;
  c.structures["particle/sorted/half"] = {
      costs, 0.04, 28, {{1, 121.5, 1.8e-9, 1480.0, 2.1e-9}, {2, 121.5, 1.9e-9, 1480.0, 2.3e-9}}};
  return c;
}

SceneRecord sample_scene() {
  SceneRecord s;
  s.kind = "uniform";
  s.n = 1000;
  s.checksum = "0123456789abcdef";
  return s;
}

json file_json(const std::string& path) { return json::parse(std::ifstream(path)); }

// The message of the InputError that reading the cache throws, or "" if none.
std::string rejection(const TuningCache& cache) {
  try {
    cache.calibration();
    cache.choice(sample_scene(), 0.05, 2);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

// `--cache tuning.json` names a file in the working folder (no folder to create); missing
// folders are made; a folder that cannot be made (a file stands where it should be) is a
// one-line InputError.
TEST(TuningCache, ABareFileNameIsSavedInTheWorkingFolder) {
  test::TempDir dir;
  const std::filesystem::path before = std::filesystem::current_path();
  std::filesystem::current_path(dir.file(""));
  TuningCache bare("tuning.json");
  EXPECT_NO_THROW(bare.store_calibration(sample_calibration()));
  std::filesystem::current_path(before);
  EXPECT_TRUE(std::filesystem::exists(dir.file("tuning.json")));
  TuningCache nested(dir.file("new/a/b/tuning.json"));
  EXPECT_NO_THROW(nested.store_calibration(sample_calibration()));
  EXPECT_TRUE(std::filesystem::is_regular_file(dir.file("new/a/b/tuning.json")));
  std::ofstream(dir.file("blocker")) << "a file, not a folder\n";
  TuningCache blocked(dir.file("blocker") + "/tuning.json");
  EXPECT_THROW(blocked.store_calibration(sample_calibration()), InputError);
}

// An MPI run's choice (its setting: mode, ranks) is its own entry; a calibration sent between
// processes as text reads back whole.
TEST(TuningCache, ASettingKeepsChoicesApartAndACalibrationTravelsAsText) {
  test::TempDir dir;
  TuningCache cache(dir.file("tuning.json"));
  const Variant serial = parse_variant("cell/morton/full/dynamic,64");
  const Variant ranks4 = parse_variant("particle/sorted/full/static,8");
  cache.store_choice(sample_scene(), 0.05, 2, serial, 0.25);
  cache.store_choice(sample_scene(), 0.05, 2, ranks4, 0.25, "mpi decomposed, 4 ranks, halo 0.05");
  EXPECT_EQ(cache.choice(sample_scene(), 0.05, 2), serial);
  EXPECT_EQ(cache.choice(sample_scene(), 0.05, 2, "mpi decomposed, 4 ranks, halo 0.05"), ranks4);
  EXPECT_FALSE(cache.choice(sample_scene(), 0.05, 2, "mpi decomposed, 3 ranks, halo 0.05"));
  const Calibration back =
      TuningCache::calibration_from_text(TuningCache::calibration_text(sample_calibration()));
  EXPECT_EQ(back.threads, 2);
  EXPECT_EQ(back.structures.at("particle/sorted/half").costs,
            sample_calibration().structures.at("particle/sorted/half").costs);
  EXPECT_EQ(back.structures.at("particle/sorted/half").output,
            sample_calibration().structures.at("particle/sorted/half").output);
  EXPECT_THROW(TuningCache::calibration_from_text(R"({"seconds": 1})"), InputError);
}

TEST(TuningCache, StoredEntriesReadBack) {
  test::TempDir dir;
  TuningCache cache(dir.file("tuning.json"));
  EXPECT_FALSE(cache.calibration().has_value());
  cache.store_calibration(sample_calibration());
  const Variant variant = parse_variant("cell/morton/full/dynamic,64");
  cache.store_choice(sample_scene(), 0.05, 2, variant, 0.25);
  const auto calibration = cache.calibration();
  ASSERT_TRUE(calibration.has_value());
  EXPECT_EQ(calibration->source, "cache");
  EXPECT_EQ(calibration->threads, 2);
  const StructureCosts& s = calibration->structures.at("particle/sorted/half");
  EXPECT_EQ(s.costs, sample_calibration().structures.at("particle/sorted/half").costs);
  EXPECT_EQ(s.runs, 28);
  EXPECT_EQ(s.output, sample_calibration().structures.at("particle/sorted/half").output);
  EXPECT_EQ(cache.choice(sample_scene(), 0.05, 2), variant);
  EXPECT_FALSE(cache.choice(sample_scene(), 0.05, 4).has_value());
  const json j = file_json(cache.path());
  EXPECT_EQ(j["schema_version"], 1);
  const json& stored = j["calibrations"].begin()->at("structures").begin()->at("costs");
  for (const auto& [name, member] : kMachineCostFields) EXPECT_TRUE(stored.contains(name)) << name;
  EXPECT_EQ(stored.at("seconds_per_weighed_iteration"), 9e-10);
  EXPECT_EQ(stored.at("seconds_per_weighed_build"), 0.0);
}

TEST(TuningCache, AnotherCostModelIsAMiss) {
  test::TempDir dir;
  TuningCache cache(dir.file("tuning.json"));
  cache.store_calibration(sample_calibration());
  json j = file_json(cache.path());
  json& entry = *j["calibrations"].begin();
  entry["cost_model_version"] = 1;
  entry["structures"].begin()->at("costs")["seconds_per_retired_constant"] = 1.0;
  std::ofstream(cache.path()) << j.dump();
  EXPECT_FALSE(cache.calibration().has_value());
}

TEST(TuningCache, MalformedFilesNameTheFileAndThePath) {
  test::TempDir dir;
  TuningCache cache(dir.file("tuning.json"));
  cache.store_calibration(sample_calibration());
  cache.store_choice(sample_scene(), 0.05, 2, parse_variant("particle/sorted/half/static"), 0.1);
  const json good = file_json(cache.path());
  json j = good;
  j["schema_version"] = 2;
  std::ofstream(cache.path(), std::ios::trunc) << j.dump();
  EXPECT_NE(rejection(cache).find("$.schema_version: version 2 is not supported"),
            std::string::npos);
  j = good;
  j["choices"].begin()->erase("detect_s");
  std::ofstream(cache.path(), std::ios::trunc) << j.dump();
  const std::string missing = rejection(cache);
  EXPECT_NE(missing.find(cache.path()), std::string::npos) << missing;
  EXPECT_NE(missing.find("missing field 'detect_s'"), std::string::npos) << missing;
  j = good;
  j["calibrations"].begin()->at("structures").begin()->at("costs").erase("seconds_per_grab");
  std::ofstream(cache.path(), std::ios::trunc) << j.dump();
  EXPECT_NE(rejection(cache).find(".costs: missing field 'seconds_per_grab'"), std::string::npos);
}

}  // namespace
}  // namespace contactlab::tuner
