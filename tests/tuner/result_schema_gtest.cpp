// The result schema: a real run survives a write/read round trip unchanged; the strict reader
// rejects unknown, missing and mistyped fields with the JSON path; the documented example is valid.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <set>
#include <sstream>

#include "contactlab/kernels/error.hpp"
#include "contactlab/tuner/measure.hpp"
#include "contactlab/tuner/result_schema.hpp"
#include "program_test_support.hpp"

namespace contactlab::tuner {
namespace {

using nlohmann::json;

// One real measurement with a context, plus a simulated counter record and a failed run, so
// that every optional part of the schema is filled somewhere.
ResultFile sample_result() {
  const SceneSpec spec = test::small_clustered(3000);
  const Scene scene = generate_scene(spec);
  DetectOptions options{parse_variant("cell/sorted/static"), spec.diameter, 2, nullptr};
  MeasureOptions measure;
  measure.repetition.warmup = 1;
  measure.repetition.repeat = 4;
  ContactDetector detector;
  ResultFile file;
  file.context = collect_context("contactlab detect --test", 2);
  RunRecord run =
      measure_detection(detector, scene, describe_generated_scene(spec, scene), options, measure);
  CounterRecord simulated;
  simulated.source = "simulated:fx10";
  simulated.available = true;
  simulated.l1_miss_percent = 4.5;
  simulated.l2_miss_percent = 0.41;
  simulated.l1_formula = "100 * (D1mr + D1mw) / (Dr + Dw)";
  simulated.l2_formula = "100 * (DLmr + DLmw) / (Dr + Dw)";
  simulated.counted_runs = 1;
  simulated.events = {{"Dr", 1000, {}}, {"D1mr", 45, {}}};
  simulated.simulation =
      SimulationRecord{CacheGeometry{"fx10", {32768, 2, 128}, {12582912, 24, 128}, "x", true},
                       "valgrind",
                       1,
                       0.5,
                       "/usr/bin/contactlab-cachesim",
                       "x86-64",
                       222,
                       "off"};
  run.counters.push_back(simulated);
  CounterRecord papi;
  papi.source = "papi";
  papi.available = false;
  papi.reason = "PAPI_L1_DCM: Event does not exist";
  run.counters.push_back(papi);
  file.runs.push_back(run);
  file.runs.push_back(failed_run(run.parameters, "out of memory"));
  return file;
}

const json& sample_json() {
  static const json j = sample_result();
  return j;
}

// The message of the SchemaError that parse_result throws for `j`, or "" if none.
std::string rejection(const json& j) {
  try {
    parse_result(j);
  } catch (const SchemaError& e) {
    return e.what();
  }
  return "";
}

TEST(ResultSchema, RoundTripIsExact) {
  const json& original = sample_json();
  const ResultFile parsed = parse_result(original);
  const json again = parsed;
  EXPECT_EQ(again, original);
  ASSERT_EQ(parsed.runs.size(), 2u);
  EXPECT_EQ(parsed.runs[0].status, RunStatus::kOk);
  EXPECT_EQ(parsed.runs[0].samples.total_s.size(), 4u);
  EXPECT_EQ(parsed.runs[0].samples.thread_busy_s[0].size(), 2u);
  EXPECT_EQ(parsed.runs[1].status, RunStatus::kFailed);
  EXPECT_FALSE(parsed.runs[1].aggregates.has_value());
  EXPECT_EQ(parsed.context.openmp.threads, 2);
}

TEST(ResultSchema, RoundTripThroughAFile) {
  test::TempDir dir;
  const std::string path = dir.file("r.json");
  write_result_file(path, parse_result(sample_json()));
  const json again = read_result_file(path);
  EXPECT_EQ(again, sample_json());
}

TEST(ResultSchema, RecordsWhatEveryResultNeeds) {
  const json& j = sample_json();
  EXPECT_EQ(j["schema_version"], kSchemaVersion);
  EXPECT_TRUE(j["context"]["build"].contains("git_commit"));
  EXPECT_TRUE(j["context"]["machine"]["cores"].get<int>() >= 1);
  EXPECT_TRUE(j["context"]["papi"].contains("version"));
  const json& run = j["runs"][0];
  EXPECT_EQ(run["aggregates"]["total_s"]["count"], 4);
  EXPECT_EQ(run["samples"]["imbalance"].size(), 4u);
  for (const auto& c : run["counters"]) {
    EXPECT_TRUE(c["source"] == "papi" ||
                c["source"].get<std::string>().rfind("simulated:", 0) == 0);
  }
}

TEST(ResultSchema, RejectsUnknownFieldsWithThePath) {
  json j = sample_json();
  j["runs"][0]["parameters"]["colour"] = "blue";
  EXPECT_EQ(rejection(j), "$.runs[0].parameters: unknown field 'colour'");
  j = sample_json();
  j["extra"] = 1;
  EXPECT_EQ(rejection(j), "$: unknown field 'extra'");
  j = sample_json();
  j["runs"][0]["counters"][0]["simulation"]["geometry"]["l1"]["prefetch"] = true;
  EXPECT_EQ(rejection(j), "$.runs[0].counters[0].simulation.geometry.l1: unknown field 'prefetch'");
}

TEST(ResultSchema, RejectsMissingFieldsWithThePath) {
  json j = sample_json();
  j["context"]["machine"].erase("cores");
  EXPECT_EQ(rejection(j), "$.context.machine: missing field 'cores'");
  j = sample_json();
  j["runs"][1].erase("status");
  EXPECT_EQ(rejection(j), "$.runs[1]: missing field 'status'");
  j = sample_json();
  j["context"]["openmp"]["env"].erase("OMP_PLACES");
  EXPECT_EQ(rejection(j), "$.context.openmp.env: missing field 'OMP_PLACES'");
}

TEST(ResultSchema, RejectsWrongTypesWithThePath) {
  json j = sample_json();
  j["runs"][0]["samples"]["setup_s"][2] = "fast";
  EXPECT_EQ(rejection(j), "$.runs[0].samples.setup_s[2]: expected number, got string");
  j = sample_json();
  j["runs"][0]["work"]["contact_pairs"] = -3;
  EXPECT_EQ(rejection(j), "$.runs[0].work.contact_pairs: expected non-negative integer, got -3");
  j = sample_json();
  j["runs"][0]["parameters"]["threads"] = 2.5;
  EXPECT_EQ(rejection(j), "$.runs[0].parameters.threads: expected integer, got number");
  j = sample_json();
  j["runs"] = json::object();
  EXPECT_EQ(rejection(j), "$.runs: expected array, got object");
  EXPECT_EQ(rejection(json::array()), "$: expected object, got array");
}

TEST(ResultSchema, RejectsInconsistentRecords) {
  json j = sample_json();
  j["schema_version"] = 2;
  EXPECT_NE(rejection(j).find("$.schema_version: unsupported schema_version 2"), std::string::npos);
  j = sample_json();
  j["runs"][0]["status"] = "great";
  EXPECT_NE(rejection(j).find("$.runs[0]: status: unknown run status 'great'"), std::string::npos);
  j = sample_json();
  j["runs"][0]["counters"][1]["reason"] = "";
  EXPECT_EQ(rejection(j), "$.runs[0].counters[1]: available is false but no reason is given");
  j = sample_json();
  j["runs"][0]["counters"][1]["l1_miss_percent"] = 0.0;  // a silent zero
  EXPECT_EQ(rejection(j), "$.runs[0].counters[1]: miss rates given although available is false");
  j = sample_json();
  j["runs"][0]["counters"][0]["source"] = "guessed";
  EXPECT_NE(rejection(j).find("$.runs[0].counters[0]: source 'guessed'"), std::string::npos);
  j = sample_json();
  j["runs"][0]["counters"][0]["simulation"] = nullptr;
  EXPECT_EQ(rejection(j),
            "$.runs[0].counters[0]: a simulated source needs its 'simulation' record");
  j = sample_json();
  j["runs"][0]["samples"]["detect_s"].push_back(1.0);
  EXPECT_NE(rejection(j).find("$.runs[0].samples: "), std::string::npos);
  j = sample_json();
  j["runs"][0]["aggregates"] = nullptr;
  EXPECT_EQ(rejection(j), "$.runs[0]: a run with status 'ok' needs aggregates and work");
  j = sample_json();
  j["runs"][1]["message"] = "";
  EXPECT_EQ(rejection(j), "$.runs[1]: a run with status 'failed' needs a message");
  j = sample_json();
  j["runs"][0]["aggregates"]["stop_reason"] = "tired";
  EXPECT_NE(rejection(j).find("$.runs[0].aggregates: stop_reason: unknown stop reason 'tired'"),
            std::string::npos);
}

// A sweep's later round adds its samples to the point's record, tagged with the round; the tags
// are written only where there are rounds, and must match the samples.
TEST(ResultSchema, VisitsOfLaterRoundsJoinTheRecordWithTheirRound) {
  const ResultFile file = sample_result();
  EXPECT_FALSE(json(file)["runs"][0]["samples"].contains("round"));
  RunRecord record = file.runs[0];
  add_visit(record, file.runs[0], 2);
  ASSERT_TRUE(record.samples.round);
  EXPECT_EQ(*record.samples.round, (std::vector<int>{0, 0, 0, 0, 2, 2, 2, 2}));
  EXPECT_EQ(record.aggregates->repetitions, 8);
  EXPECT_EQ(record.aggregates->warmup_runs, 2);
  EXPECT_EQ(record.status, RunStatus::kOk);
  EXPECT_EQ(record.phases.at("detect").median, record.aggregates->detect_s.median);
  ResultFile with_rounds = file;
  with_rounds.runs[0] = record;
  const json j = with_rounds;
  EXPECT_EQ(j["runs"][0]["samples"]["round"].size(), 8u);
  EXPECT_EQ(json(parse_result(j)), j);
  json bad = j;
  bad["runs"][0]["samples"]["round"].erase(0);
  EXPECT_NE(rejection(bad).find("$.runs[0].samples: "), std::string::npos);
  bad = j;
  bad["runs"][0]["samples"]["round"][0] = -1;
  EXPECT_EQ(rejection(bad), "$.runs[0].samples: round: rounds are numbered from 0");
  // Another contact count in a later round makes the record invalid.
  RunRecord other = file.runs[0];
  other.work->contact_pairs += 1;
  add_visit(record, other, 3);
  EXPECT_EQ(record.status, RunStatus::kInvalid);
  EXPECT_NE(record.message.find("contact count differs between rounds"), std::string::npos);
}

// T_s's parts (the sort and the reordering) and T_c's assembly, per repetition and summarised
// under their names, so that a run on many cores says which part stops scaling (issue #47).
TEST(ResultSchema, PartsOfThePhasesArePerRepetitionAndSummarised) {
  const ResultFile file = sample_result();
  const RunRecord& run = file.runs[0];
  const RunSamples& s = run.samples;
  for (const char* name : {"registration", "reorder", "assembly"}) {
    ASSERT_EQ(s.parts_s.count(name), 1u) << name;
    ASSERT_EQ(s.parts_s.at(name).size(), s.setup_s.size()) << name;
    EXPECT_EQ(json(run.phases.at(name)), json(summarize(s.parts_s.at(name), 0.95))) << name;
  }
  for (std::size_t r = 0; r < s.setup_s.size(); ++r) {
    const double registration = s.parts_s.at("registration")[r];
    const double reorder = s.parts_s.at("reorder")[r];
    EXPECT_GT(registration, 0.0);
    EXPECT_GT(reorder, 0.0);
    EXPECT_LE(registration + reorder, s.setup_s[r]) << "both timed inside T_s";
    EXPECT_LE(s.parts_s.at("assembly")[r], s.detect_s[r]);
  }
  const json j = file;
  EXPECT_EQ(json(parse_result(j)), j);
  json bad = j;
  bad["runs"][0]["samples"]["parts_s"]["reorder"].erase(0);
  EXPECT_EQ(rejection(bad),
            "$.runs[0].samples: parts_s: reorder must have one entry per repetition");
  // A file from before the parts reads with none, and a visit without them drops them.
  json old = j;
  old["runs"][0]["samples"].erase("parts_s");
  EXPECT_TRUE(parse_result(old).runs[0].samples.parts_s.empty());
  RunRecord joined = run;
  add_visit(joined, run, 1);
  EXPECT_EQ(joined.samples.parts_s.at("reorder").size(), 2 * s.setup_s.size());
  RunRecord older = run;
  older.samples.parts_s.clear();
  add_visit(joined, older, 2);
  EXPECT_TRUE(joined.samples.parts_s.empty());
  EXPECT_EQ(joined.phases.count("reorder"), 0u);
  EXPECT_EQ(joined.phases.count("setup"), 1u);
}

TEST(ResultSchema, FileErrorsNameTheFile) {
  test::TempDir dir;
  const std::string path = dir.file("broken.json");
  std::ofstream(path) << "{ not json";
  try {
    read_result_file(path);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos);
  }
  std::ofstream(path, std::ios::trunc) << "{\"schema_version\": 1}";
  try {
    read_result_file(path);
    FAIL() << "expected SchemaError";
  } catch (const SchemaError& e) {
    EXPECT_EQ(std::string(e.what()), path + ": $: missing field 'context'");
  }
  EXPECT_THROW(read_result_file(dir.file("absent.json")), InputError);
}

// The example in docs/result-schema.md must be a valid result file.
TEST(ResultSchema, DocumentedExampleIsValid) {
  std::ifstream in(std::string(CONTACTLAB_SOURCE_DIR) + "/docs/result-schema.md");
  ASSERT_TRUE(in) << "docs/result-schema.md not found";
  std::stringstream text;
  text << in.rdbuf();
  const std::string doc = text.str();
  const auto start = doc.find("```json\n");
  ASSERT_NE(start, std::string::npos) << "no ```json block in docs/result-schema.md";
  const auto body = start + 8;
  const auto end = doc.find("```", body);
  const json example = json::parse(doc.substr(body, end - body));
  const ResultFile parsed = parse_result(example);
  EXPECT_FALSE(parsed.runs.empty());
}

TEST(ResultSchema, RunsNameTheirPhasesAndWorkCounts) {
  const ResultFile parsed = parse_result(sample_json());
  const RunRecord& run = parsed.runs[0];
  // T_s and T_c, and their parts (PartsOfThePhasesArePerRepetitionAndSummarised).
  ASSERT_EQ(run.phases.size(), 5u);
  EXPECT_EQ(json(run.phases.at("setup")), json(run.aggregates->setup_s));
  EXPECT_EQ(json(run.phases.at("detect")), json(run.aggregates->detect_s));
  EXPECT_EQ(run.work_counts.at("candidate_tests"), run.work->candidate_tests);
  EXPECT_EQ(run.work_counts.at("contact_pairs"), run.work->contact_pairs);
  EXPECT_EQ(run.work_counts.at("max_cell_occupancy"), run.work->max_cell_occupancy);
  EXPECT_TRUE(parsed.runs[1].phases.empty());
  EXPECT_EQ(sample_json()["runs"][1]["work_counts"], json::object());
  json j = sample_json();
  j["runs"][0]["work_counts"]["contact_pairs"] = -1;
  EXPECT_EQ(rejection(j),
            "$.runs[0].work_counts.contact_pairs: expected non-negative integer, got -1");
  j = sample_json();
  j["runs"][0]["phases"]["setup"].erase("median");
  EXPECT_EQ(rejection(j), "$.runs[0].phases.setup: missing field 'median'");
  j = sample_json();
  j["runs"][0]["phases"] = json::array();
  EXPECT_EQ(rejection(j), "$.runs[0].phases: expected object, got array");
}

// Files written before phases and work_counts existed still read, with both empty.
TEST(ResultSchema, RunsWithoutPhasesStillRead) {
  json j = sample_json();
  for (auto& run : j["runs"]) {
    run.erase("phases");
    run.erase("work_counts");
  }
  const ResultFile parsed = parse_result(j);
  EXPECT_TRUE(parsed.runs[0].phases.empty());
  EXPECT_TRUE(parsed.runs[0].work_counts.empty());
}

// Every committed result file (an object with "schema_version" and "runs") reads strictly, and
// writing what was read gives the same JSON again, but for the fields the file predates (added
// with their empty values).
TEST(ResultSchema, CommittedResultFilesRead) {
  namespace fs = std::filesystem;
  const std::set<std::string> newer{"phases",      "work_counts",     "executable", "code_isa",
                                    "simd_target", "candidate_tests", "parts_s"};
  int files = 0;
  for (const auto& entry :
       fs::recursive_directory_iterator(fs::path(CONTACTLAB_SOURCE_DIR) / "results")) {
    if (!entry.is_regular_file() || entry.path().extension() != ".json") continue;
    std::ifstream in(entry.path());
    const json j = json::parse(in);
    if (!j.is_object() || !j.contains("schema_version") || !j.contains("runs")) continue;
    ResultFile parsed;
    ASSERT_NO_THROW(parsed = read_result_file(entry.path().string())) << entry.path();
    for (const json& change : json::diff(j, json(parsed))) {
      const std::string path = change["path"];
      EXPECT_TRUE(change["op"] == "add" && newer.count(path.substr(path.rfind('/') + 1)))
          << entry.path() << ": " << change.dump();
    }
    ++files;
  }
  EXPECT_GT(files, 0) << "no result files under results/";
}

}  // namespace
}  // namespace contactlab::tuner
