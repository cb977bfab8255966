// Experiment configs: the documented example and the shipped configs parse; every kind of bad
// field is rejected with its JSON path; the interleaved order is seeded and complete.
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <set>

#include "contactlab/kernels/detector.hpp"
#include "contactlab/kernels/error.hpp"
#include "contactlab/tuner/experiment.hpp"

namespace contactlab::tuner {
namespace {

using nlohmann::json;

json minimal() {
  return json::parse(R"({
    "schema_version": 1, "name": "t",
    "scenes": [{"kind": "clustered", "n": 1000, "diameter": 0.02}],
    "variants": ["particle/sorted/static"], "threads": [1, 2]})");
}

std::string error_of(const json& document) {
  try {
    parse_experiment(document, "cfg.json");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

// threads 0 means what --threads 0 means everywhere: OpenMP's default team size.
TEST(Experiment, ZeroThreadsIsOpenMPsDefault) {
  json d = minimal();
  d["threads"] = {0, 3};
  const Experiment e = parse_experiment(d, "cfg.json");
  EXPECT_EQ(e.threads, (std::vector<int>{resolve_threads(0), 3}));
}

TEST(Experiment, ShippedConfigsParse) {
  for (const char* name : {"paper-tables", "table6-cache", "chunk-study", "smoke"}) {
    const Experiment e =
        read_experiment(std::string(CONTACTLAB_SOURCE_DIR) + "/experiments/" + name + ".json");
    EXPECT_FALSE(e.variants().empty()) << name;
    EXPECT_FALSE(experiment_points(e).empty()) << name;
  }
}

TEST(Experiment, ExpandsChunkPatternsAndDefaults) {
  json d = minimal();
  d["chunks"] = {{"from", 1}, {"to", 8}, {"factor", 2}};
  d["variants"] = {"particle/sorted/static,{k}", "particle/sorted/full/static,4",
                   "cell/unsorted/static"};
  const Experiment e = parse_experiment(d, "cfg.json");
  const auto variants = e.variants();
  ASSERT_EQ(variants.size(), 5u);  // k = 1, 2, 4, 8 (static,4 twice counts once), cell
  EXPECT_EQ(to_string(variants[0]), "particle/sorted/full/static,1");
  EXPECT_EQ(to_string(variants[3]), "particle/sorted/full/static,8");
  EXPECT_EQ(e.repetitions.warmup, 1);
  EXPECT_TRUE(e.check_contacts);
}

TEST(Experiment, RejectsBadFieldsWithTheirPath) {
  struct Case {
    std::function<void(json&)> edit;
    std::string expected;
  };
  const std::vector<Case> cases{
      {[](json& d) { d["colour"] = "red"; }, "$: unknown field 'colour'"},
      {[](json& d) { d.erase("threads"); }, "$: missing field 'threads'"},
      {[](json& d) { d["schema_version"] = 2; }, "$.schema_version: version 2 is not supported"},
      {[](json& d) { d["scenes"][0]["n"] = -5; },
       "$.scenes[0].n: expected non-negative integer, got -5"},
      {[](json& d) { d["scenes"][0]["kind"] = "fractal"; }, "$.scenes[0].kind: unknown scene kind"},
      {[](json& d) { d["scenes"][0]["diameter"] = 0; }, "$.scenes[0].diameter: must be in"},
      {[](json& d) { d["scenes"][0]["extra"] = 1; }, "$.scenes[0]: unknown field 'extra'"},
      {[](json& d) { d["variants"] = {"particle/shuffled/static"}; },
       "$.variants[0]: unknown order"},
      {[](json& d) { d["variants"] = {"particle/sorted/static,{k}"}; },
       "$.variants[0]: uses {k} but $.chunks is missing"},
      {[](json& d) { d["threads"] = {-1}; }, "$.threads[0]: thread counts must be in [0, 4096]"},
      {[](json& d) {
         d["repetitions"] = {{"min", 0}};
       },
       "$.repetitions.min: must be in"},
      {[](json& d) {
         d["repetitions"] = {{"min", 3}, {"target_ci", 0.02}, {"rounds", 4}};
       },
       "$.repetitions.rounds: rounds > 1 times a fixed count per visit"},
      {[](json& d) {
         d["repetitions"] = {{"rounds", 0}};
       },
       "$.repetitions.rounds: must be in"},
      {[](json& d) {
         d["measurements"] = {{"cache_sim", "l3"}};
       },
       "$.measurements.cache_sim: expected"},
      {[](json& d) {
         d["chunks"] = {1, 0};
       },
       "$.chunks[1]: chunk sizes must be >= 1"},
      {[](json& d) { d["name"] = 3; }, "$.name: expected string"},
  };
  for (const Case& c : cases) {
    json d = minimal();
    c.edit(d);
    const std::string message = error_of(d);
    EXPECT_NE(message.find("cfg.json: " + c.expected), std::string::npos) << "got: " << message;
  }
}

TEST(Experiment, UnreadableFilesAreOneLineErrors) {
  EXPECT_THROW(read_experiment("/nonexistent/config.json"), InputError);
  const std::string path = testing::TempDir() + "/broken.json";
  std::ofstream(path) << "{ not json";
  try {
    read_experiment(path);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("not valid JSON"), std::string::npos);
  }
}

TEST(Experiment, PointsAreEveryCombinationInASeededInterleavedOrder) {
  json d = minimal();
  d["scenes"].push_back({{"kind", "uniform"}, {"n", 500}, {"diameter", 0.05}});
  d["chunks"] = {1, 2, 4, 8, 16};
  d["variants"] = {"particle/sorted/static,{k}"};
  const Experiment e = parse_experiment(d, "cfg.json");
  const auto points = experiment_points(e);
  ASSERT_EQ(points.size(), 2u * 5u * 2u);
  std::set<std::string> keys;
  for (const auto& p : points) keys.insert(p.key());
  EXPECT_EQ(keys.size(), points.size());
  // Same seed, same order; another seed, another order; not grouped by scene.
  const auto again = experiment_points(e);
  for (std::size_t i = 0; i < points.size(); ++i) EXPECT_EQ(points[i].key(), again[i].key());
  Experiment other = e;
  other.order_seed = 2;
  const auto reordered = experiment_points(other);
  bool differs = false;
  for (std::size_t i = 0; i < points.size(); ++i) differs |= points[i].key() != reordered[i].key();
  EXPECT_TRUE(differs);
  std::size_t scene_changes = 0;
  for (std::size_t i = 1; i < points.size(); ++i)
    scene_changes += points[i].scene != points[i - 1].scene;
  EXPECT_GT(scene_changes, 3u);
  // Each round its own order of the same points; round 0 is the seed's order.
  const auto round0 = experiment_points(e, 0);
  const auto round1 = experiment_points(e, 1);
  std::set<std::string> keys1;
  bool round_differs = false;
  for (std::size_t i = 0; i < points.size(); ++i) {
    EXPECT_EQ(round0[i].key(), points[i].key());
    keys1.insert(round1[i].key());
    round_differs |= round1[i].key() != points[i].key();
  }
  EXPECT_EQ(keys1, keys);
  EXPECT_TRUE(round_differs);
}

TEST(Experiment, RoundsDefaultToOne) {
  EXPECT_EQ(parse_experiment(minimal(), "cfg.json").rounds, 1);
  json d = minimal();
  d["repetitions"] = {{"min", 2}, {"rounds", 5}};
  const Experiment e = parse_experiment(d, "cfg.json");
  EXPECT_EQ(e.rounds, 5);
  EXPECT_EQ(e.repetitions.repeat, 2);
  EXPECT_FALSE(e.repetitions.adaptive);
}

}  // namespace
}  // namespace contactlab::tuner
