// The tuner under mpiexec (docs/mpi.md, "Tuning"): `detect --mpi ... --variant auto` at 1 to 4
// ranks in both modes gives the serial contacts and records the choice (the run itself checks
// that every rank chose alike), the choice is cached per mode and rank count, and `tune --mpi`
// writes one report, read back strictly, with the mode and the rank count. They share the
// calibrated cache of the tune tests (fixture tune_cache), without its choices.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <utility>
#include <vector>

#include "contactlab/kernels/scene_generate.hpp"
#include "contactlab/kernels/scene_io.hpp"
#include "contactlab/tuner/result_schema.hpp"
#include "contactlab/tuner/tune_report.hpp"
#include "mpi_cli_support.hpp"
#include "program_test_support.hpp"

namespace contactlab::test {
namespace {

using nlohmann::json;

// The calibrated cache of the tune tests, without choices, as "CONTACTLAB_CACHE_DIR=... ".
std::string fresh_cache(const TempDir& dir) {
  json cache = json::parse(std::ifstream(std::string(CONTACTLAB_TUNE_CACHE_DIR) + "/tuning.json"));
  cache["choices"] = json::object();
  std::ofstream(dir.file("tuning.json")) << cache.dump();
  return "CONTACTLAB_CACHE_DIR=" +
         std::filesystem::path(dir.file("tuning.json")).parent_path().string() + " ";
}

// The variant of the "--variant auto: <variant> (stored in|from ...)" line.
std::string auto_line_variant(const std::string& output, const std::string& how) {
  const std::string tag = "--variant auto: ";
  for (auto pos = output.find(tag); pos != std::string::npos; pos = output.find(tag, pos + 1)) {
    const auto start = pos + tag.size();
    const auto end = output.find(' ', start);
    if (output.compare(end, how.size() + 2, " (" + how) == 0)
      return output.substr(start, end - start);
  }
  return {};
}

// Auto under mpiexec at 1 to 4 ranks: the serial contacts, the tuned variant in the record and
// the cache, a second run finding it there.
void check_auto(const std::string& mode, const std::string& scene_options,
                const std::string& serial_csv, const TempDir& dir) {
  const std::string env = fresh_cache(dir);
  for (int ranks = 1; ranks <= 4; ++ranks) {
    SCOPED_TRACE(mode + " at " + std::to_string(ranks) + " ranks");
    const std::string csv = dir.file("auto.csv"), record = dir.file("auto.json");
    const std::string command = env + mpiexec(ranks) + contactlab_exe() + " detect" +
                                scene_options + " --threads 1 --mpi " + mode +
                                " --variant auto --contacts-out " + csv + " --json " + record;
    const auto tuned = run_command(command);
    ASSERT_EQ(tuned.exit_code, 0) << tuned.output;
    EXPECT_EQ(slurp(csv), slurp(serial_csv));
    const std::string chosen = auto_line_variant(tuned.output, "stored in");
    ASSERT_FALSE(chosen.empty()) << tuned.output;
    EXPECT_EQ(count_of(tuned.output, "--variant auto: "), 2) << "rank 0 alone speaks";
    const tuner::ResultFile result = tuner::read_result_file(record);
    ASSERT_EQ(result.runs.size(), 1u);
    EXPECT_EQ(result.runs[0].parameters.variant, chosen);
    ASSERT_TRUE(result.runs[0].mpi.has_value());
    EXPECT_EQ(result.runs[0].mpi->ranks, ranks);
    if (mode == "decomposed") {
      EXPECT_NE(chosen.find("/full/"), std::string::npos) << chosen;
    }
    if (ranks == 2) {
      const auto cached = run_command(command);
      ASSERT_EQ(cached.exit_code, 0) << cached.output;
      EXPECT_EQ(auto_line_variant(cached.output, "from"), chosen) << cached.output;
      EXPECT_EQ(slurp(csv), slurp(serial_csv));
    }
  }
  // One choice per mode and rank count, apart from the serial one's.
  const json cache = json::parse(std::ifstream(dir.file("tuning.json")));
  EXPECT_EQ(cache["choices"].size(), 4u) << cache["choices"].dump(1);
}

TEST(TuneMpi, VariantAutoReplicatedGivesTheSerialContacts) {
  TempDir dir;
  const std::string scene = " --scene clustered --n 3000 -D 0.02 --seed 3";
  const auto serial =
      run_command(contactlab_exe() + " detect" + scene +
                  " --threads 1 --repeat 1 --warmup 0 --contacts-out " + dir.file("serial.csv"));
  ASSERT_EQ(serial.exit_code, 0) << serial.output;
  check_auto("replicated", scene + " --block 50", dir.file("serial.csv"), dir);
}

// A binary file read in shares; the clusters straddle the subdomains' boundaries.
TEST(TuneMpi, VariantAutoDecomposedGivesTheSerialContacts) {
  TempDir dir;
  const std::string path = dir.file("scene.bin");
  SceneSpec spec;
  spec.kind = SceneKind::kBlobs;
  spec.n = 4000;
  spec.diameter = 0.02;
  spec.blob_count = 3;
  write_binary_scene(generate_scene(spec), path);
  const std::string scene = " --input " + path + " -D 0.02";
  const auto serial =
      run_command(contactlab_exe() + " detect" + scene +
                  " --threads 1 --repeat 1 --warmup 0 --contacts-out " + dir.file("serial.csv"));
  ASSERT_EQ(serial.exit_code, 0) << serial.output;
  check_auto("decomposed", scene, dir.file("serial.csv"), dir);
}

TEST(TuneMpi, TuneWritesOneStrictReportWithTheModeAndRanks) {
  TempDir dir;
  const std::string env = fresh_cache(dir);
  // Each rank count once over the two modes.
  for (const auto& [mode, ranks] : std::vector<std::pair<std::string, int>>{
           {"replicated", 1}, {"replicated", 4}, {"decomposed", 2}, {"decomposed", 3}}) {
    SCOPED_TRACE(mode + " at " + std::to_string(ranks) + " ranks");
    const std::string report = dir.file("tune.json");
    const auto run = run_command(
        env + mpiexec(ranks) + contactlab_exe() +
        " tune --scene clustered --n 3000 -D 0.02 --threads 1 --max-chunk 64 --search-samples 1"
        " --verify-rounds 5 --mpi " +
        mode + " --json " + report);
    ASSERT_EQ(run.exit_code, 0) << run.output;
    EXPECT_EQ(count_of(run.output, "every time is the slowest rank's"), 1) << run.output;
    const tuner::TuneDocument t = tuner::read_tune_document(report);
    ASSERT_TRUE(t.mpi.has_value());
    EXPECT_EQ(t.mpi->mode, mode);
    EXPECT_EQ(t.mpi->ranks, ranks);
    EXPECT_EQ(t.threads, 1);
    ASSERT_EQ(t.methods.size(), 2u);
    EXPECT_TRUE(t.verification.has_value());
    for (const auto& m : t.methods) {
      if (mode == "decomposed") {
        EXPECT_NE(m.variant.find("/full/"), std::string::npos) << m.variant;
      }
      EXPECT_TRUE(m.measured.has_value());
    }
  }
}

TEST(TuneMpi, ABadOptionOnEveryRankGivesOneMessage) {
  TempDir dir;
  const std::string env = fresh_cache(dir);
  for (const std::string options :
       {"--mpi sideways", "--mpi decomposed --orders nowhere", "--mpi replicated --block 0",
        "--mpi decomposed --max-chunk 0"}) {
    const auto run = run_command(env + mpiexec(2) + contactlab_exe() +
                                 " tune --scene uniform --n 500 -D 0.02 --threads 1 " + options);
    EXPECT_NE(run.exit_code, 0) << options << ": " << run.output;
    EXPECT_EQ(count_of(run.output, "contactlab: error:"), 1) << options << ": " << run.output;
  }
}

}  // namespace
}  // namespace contactlab::test
