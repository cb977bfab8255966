// The tune report as types: written and read back through its field tables, a method's own
// fields present only where it has them, and bad documents rejected with their JSON path.
#include <gtest/gtest.h>

#include "contactlab/kernels/error.hpp"
#include "contactlab/tuner/context.hpp"
#include "contactlab/tuner/tune_report.hpp"

namespace contactlab::tuner {
namespace {

TuneDocument sample_document() {
  TuneDocument d;
  d.context = collect_context("contactlab tune", 2);
  d.scene.kind = "clustered";
  d.scene.n = 1000;
  d.scene.checksum = "0123456789abcdef";
  d.scene.box = {0, 0, 0, 1, 1, 1};
  d.diameter = 0.01;
  d.threads = 2;
  d.chunk_grid = {1, 2, 4};
  d.calibration = {"cache", 61.5};
  MethodEntry model;
  model.method = "model";
  model.variant = "particle/sorted/half/dynamic,4";
  model.chunk = 4;
  model.predicted_s = 0.01;
  model.structures = nlohmann::json::array({{{"variant", "x"}, {"predicted_s", 0.01}}});
  model.measured = VerifiedTiming{0.02, 0.019, 0.021, {0.02, 0.019, 0.021}};
  model.regret = 0.01;
  model.regret_ci95 = std::array<double, 2>{-0.01, 0.03};
  MethodEntry search;
  search.method = "search";
  search.variant = "particle/sorted/half/dynamic,2";
  search.chunk = 2;
  search.timed_runs = 30;
  search.evaluations = 6;
  d.methods = {model, search};
  ClassicEntry classic;
  classic.name = "kruskal_weiss";
  classic.chunk = 8;
  classic.inputs = "N=1000";
  classic.structure = "particle/sorted/half";
  d.classic = {classic};
  d.predictions = {{4, "particle/sorted/half/dynamic,4", 0.005, "predicted (model only)"}};
  d.verification = VerificationSummary{30, 3, "particle/sorted/half/dynamic,2", "fastest"};
  return d;
}

TEST(TuneReport, RoundTripKeepsEveryField) {
  const TuneDocument d = sample_document();
  const nlohmann::json j = to_json_value(d);
  TuneDocument back;
  read(JsonIn(j, "$"), back);
  EXPECT_EQ(to_json_value(back), j);
  ASSERT_NE(back.method("search"), nullptr);
  EXPECT_EQ(back.method("search")->evaluations, 6);
  EXPECT_EQ(back.method("exhaustive"), nullptr);
  EXPECT_FALSE(j.contains("mpi"));  // tune --mpi only
}

TEST(TuneReport, AnMpiTuneKeepsItsModeAndRanks) {
  TuneDocument d = sample_document();
  d.mpi = TuneMpi{"decomposed", 4, 0, 0.02};
  const nlohmann::json j = to_json_value(d);
  TuneDocument back;
  read(JsonIn(j, "$"), back);
  EXPECT_EQ(to_json_value(back), j);
  ASSERT_TRUE(back.mpi.has_value());
  EXPECT_EQ(back.mpi->mode, "decomposed");
  EXPECT_EQ(back.mpi->ranks, 4);
  nlohmann::json bad = j;
  bad["mpi"]["nodes"] = 2;
  TuneDocument d2;
  EXPECT_THROW(read(JsonIn(bad, "$"), d2), InputError);
}

TEST(TuneReport, AMethodsOwnFieldsAppearOnlyWhereItHasThem) {
  const nlohmann::json j = to_json_value(sample_document());
  EXPECT_TRUE(j["methods"][0].contains("predicted_s"));
  EXPECT_FALSE(j["methods"][1].contains("predicted_s"));
  EXPECT_TRUE(j["methods"][1].contains("evaluations"));
  EXPECT_FALSE(j["methods"][1].contains("measured"));  // not verified in this sample
  EXPECT_FALSE(j["classic"][0].contains("variant"));
}

TEST(TuneReport, BadDocumentsNameTheirPath) {
  auto error_of = [](const nlohmann::json& j) -> std::string {
    try {
      TuneDocument d;
      read(JsonIn(j, "$"), d);
    } catch (const InputError& e) {
      return e.what();
    }
    return "";
  };
  nlohmann::json j = to_json_value(sample_document());
  j["methods"][1]["colour"] = "red";
  EXPECT_NE(error_of(j).find("$.methods[1]: unknown field 'colour'"), std::string::npos)
      << error_of(j);
  j = to_json_value(sample_document());
  j["schema_version"] = 7;
  EXPECT_NE(error_of(j).find("schema_version 7"), std::string::npos) << error_of(j);
  j = to_json_value(sample_document());
  j["predictions"][0]["label"] = "measured";
  EXPECT_NE(error_of(j).find("must say it is predicted"), std::string::npos) << error_of(j);
  j = to_json_value(sample_document());
  j["methods"] = nlohmann::json::array();
  EXPECT_NE(error_of(j).find("no tuning method ran"), std::string::npos) << error_of(j);
}

}  // namespace
}  // namespace contactlab::tuner
