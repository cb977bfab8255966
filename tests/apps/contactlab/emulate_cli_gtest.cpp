// contactlab emulate end to end: the thread emulation's document (measured with intervals,
// emulated, the anchor, the checks, the chunk study), the MPI model's series checked against a
// measured `detect --mpi` run, bad input as one line with nothing written, --json's folders
// made.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "contactlab/tuner_model/emulation.hpp"
#include "program_test_support.hpp"

namespace contactlab::test {
namespace {

using nlohmann::json;
using tuner::AmdahlPhase;
using tuner::ExchangePhase;

// The tune tests' cache (fixture tune_calibration): its calibration covers the sorted
// particle and cell loops, so these tests time only their own scene.
std::string with_cache() {
  return std::string("CONTACTLAB_CACHE_DIR=") + CONTACTLAB_TUNE_CACHE_DIR + " ";
}

const char* kScene = " --scene clustered --n 20000 -D 0.02 --seed 3";

TEST(EmulateCli, ThreadsWritesMeasuredEmulatedChecksAndChunks) {
  TempDir dir;
  const std::string out = dir.file("threads.json");
  const auto r = run_command(with_cache() + contactlab_exe() + " emulate threads" + kScene +
                             " --variants particle/sorted/full/static,cell/sorted/full/static"
                             " --threads 1,2,4,16 --measured-threads 1,2 --rounds 3"
                             " --chunk-threads 4 --json " +
                             out);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const json doc = json::parse(slurp(out));
  EXPECT_EQ(doc["kind"], "contactlab-thread-emulation");
  EXPECT_EQ(doc["label"], "emulated");
  EXPECT_EQ(doc["scene"]["n"], 20000);
  ASSERT_EQ(doc["variants"].size(), 2u);
  for (const auto& v : doc["variants"]) {
    ASSERT_EQ(v["measured"].size(), 2u);
    for (const auto& m : v["measured"]) {
      EXPECT_LE(m["total_s"]["low"].get<double>(), m["total_s"]["median"].get<double>());
      EXPECT_LE(m["total_s"]["median"].get<double>(), m["total_s"]["high"].get<double>());
    }
    ASSERT_EQ(v["emulated"].size(), 4u);
    // One thread is the anchor: the emulated T_c is the measured median.
    EXPECT_NEAR(v["emulated"][0]["detect_s"].get<double>(),
                v["measured"][0]["detect_s"]["median"].get<double>(), 1e-12);
    EXPECT_DOUBLE_EQ(v["emulated"][0]["speedup"].get<double>(), 1.0);
    EXPECT_EQ(v["emulated"][3]["threads"], 16);
    // The full stencil at one thread writes its rows in place: no copy in the anchor. At more
    // threads (static) the other threads' rows are copied, a share of the output that shrinks
    // per thread as the threads grow.
    EXPECT_EQ(v["emulated"][0]["output_s"].get<double>(), 0.0);
    EXPECT_GT(v["emulated"][1]["output_s"].get<double>(), 0.0);
    EXPECT_LT(v["emulated"][1]["output_s"].get<double>(),
              v["emulated"][1]["detect_s"].get<double>());
    EXPECT_LT(v["emulated"][3]["output_s"].get<double>(),
              v["emulated"][1]["output_s"].get<double>());
    // Static blocks are not dealt in chunks: no share timed alone, no locality factor.
    for (const auto& e : v["emulated"]) EXPECT_EQ(e["locality_factor"].get<double>(), 1.0) << e;
    ASSERT_EQ(v["validation"].size(), 1u);
    const auto& c = v["validation"][0];
    EXPECT_EQ(c["threads"], 2);
    EXPECT_NEAR(c["detect_relative_error"].get<double>(),
                c["emulated_detect_s"].get<double>() / c["measured_detect_s"].get<double>() - 1,
                1e-12);
  }
  // Both variants register and reorder alike (sorted, double, the same index): their setup is
  // fitted once from the pooled samples, so it is the same at every emulated thread count.
  for (std::size_t t = 0; t < 4; ++t) {
    EXPECT_DOUBLE_EQ(doc["variants"][0]["emulated"][t]["setup_s"].get<double>(),
                     doc["variants"][1]["emulated"][t]["setup_s"].get<double>());
  }
  ASSERT_EQ(doc["chunk_study"].size(), 2u);  // dynamic and static at 4 threads
  for (const auto& s : doc["chunk_study"]) {
    EXPECT_EQ(s["threads"], 4);
    EXPECT_EQ(s["variant"].get<std::string>().substr(0, 20), "particle/sorted/full");
    double best = 1e300;
    for (const auto& p : s["points"]) {
      best = std::min(best, p["detect_s"].get<double>());
      // Every chunk's deal at 4 threads had thread 0's share timed alone: a measured factor.
      EXPECT_GT(p["locality_factor"].get<double>(), 0.0) << p;
    }
    EXPECT_DOUBLE_EQ(s["best_detect_s"].get<double>(), best);
    // The classic formulas beside the dynamic study, none faster than its best on the grid
    // unless its chunk is off the grid.
    if (s["schedule"] == "dynamic") {
      ASSERT_FALSE(s["classic"].empty());
      for (const auto& c : s["classic"]) {
        EXPECT_GE(c["chunk"].get<int>(), 1) << c;
        EXPECT_GT(c["detect_s"].get<double>(), 0.0) << c;
      }
    } else {
      EXPECT_TRUE(s["classic"].empty());
    }
  }
}

// A machine file as `contactlab probe --json` writes it: one working set, 1 and 2 threads.
std::string write_machine_file(const TempDir& dir, double one_gb_s, double two_gb_s) {
  std::string path = dir.file("machine.json");
  json doc{{"schema_version", 1},
           {"kind", "contactlab-machine-probe"},
           {"label", "measured"},
           {"context", json::object()},
           {"method", "hand-written for the test"},
           {"working_sets",
            {{{"bytes", 1 << 30},
              {"points",
               {{{"threads", 1}, {"bytes_per_s", one_gb_s * 1e9}},
                {{"threads", 2}, {"bytes_per_s", two_gb_s * 1e9}}}}}}}};
  std::ofstream(path) << doc.dump();
  return path;
}

// With a machine file every emulated phase takes at least its bytes over the bandwidth its
// threads draw: the file, the ceiling and its source are named, each variant's bytes are given,
// and each point carries its bandwidth (the curve through the probe towards the ceiling).
TEST(EmulateCli, ThreadsPricesEveryPhaseByItsBytes) {
  TempDir dir;
  const std::string out = dir.file("threads.json");
  // 20 MB/s at one thread: a memory so slow that every phase is bound by its bytes.
  const std::string machine = write_machine_file(dir, 0.02, 0.03);
  const auto r = run_command(
      with_cache() + contactlab_exe() + " emulate threads" + kScene +
      " --variants particle/unsorted/full/static,particle/sorted/full/static"
      " --threads 1,2,16 --measured-threads 1 --rounds 1"
      " --chunk-threads 2 --machine " +
      machine + " --bandwidth-ceiling 0.04 --ceiling-source 'a test figure' --json " + out);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const json doc = json::parse(slurp(out));
  EXPECT_EQ(doc["bandwidth"]["machine_file"], machine);
  EXPECT_EQ(doc["bandwidth"]["ceiling_source"], "a test figure");
  EXPECT_DOUBLE_EQ(doc["bandwidth"]["ceiling_bytes_per_s"].get<double>(), 0.04e9);
  ASSERT_EQ(doc["variants"].size(), 2u);
  const double unsorted_loop = doc["variants"][0]["traffic"]["loop_bytes"].get<double>();
  EXPECT_GT(unsorted_loop, 2 * doc["variants"][1]["traffic"]["loop_bytes"].get<double>())
      << "a line per candidate against the sorted records streamed once";
  for (const auto& v : doc["variants"]) {
    const json& traffic = v["traffic"];
    EXPECT_EQ(traffic["working_set_bytes"], 1 << 30);
    const double bytes = traffic["setup_bytes"].get<double>() + traffic["loop_bytes"].get<double>();
    for (const auto& p : v["emulated"]) {
      const double b = p["bytes_per_s"].get<double>();
      // Through (2, 30 MB/s) towards 40: K = 2 (40/30 - 1) = 2/3, B(16) = 40 x 16 / (16 + 2/3).
      if (p["threads"] == 2) {
        EXPECT_DOUBLE_EQ(b, 0.03e9);
      } else if (p["threads"] == 16) {
        EXPECT_NEAR(b, 0.04e9 * 16 / (16 + 2.0 / 3), 1.0);
      }
      EXPECT_GE(p["setup_s"].get<double>() * (1 + 1e-12), traffic["setup_bytes"].get<double>() / b)
          << p;
      EXPECT_GE(p["detect_s"].get<double>() * (1 + 1e-12), traffic["loop_bytes"].get<double>() / b)
          << p;
      EXPECT_GE(p["memory_s"].get<double>() * (1 + 1e-12), bytes / b) << p;
    }
  }
  // Each sentence where it belongs (the bandwidth sentence once stood in the place of the most
  // measured threads, and that count before "Not modelled").
  const std::string method = doc["method"].get<std::string>();
  EXPECT_NE(method.find("measured 1- and 1-thread times less the copy"), std::string::npos)
      << method;
  EXPECT_NE(method.find("1-thread T_s. Bandwidth (the machine file in `bandwidth`): every phase"),
            std::string::npos)
      << method;
  EXPECT_NE(method.find("at least its bytes"), std::string::npos);
  EXPECT_NE(method.find("the stated ceiling. Not modelled: shared caches"), std::string::npos)
      << method;
}

// The half stencil writes every row in its assembly, measured whole: no modelled copy beside
// it, so that one thread is its anchor too.
TEST(EmulateCli, TheHalfStencilsOneThreadIsItsMeasurement) {
  TempDir dir;
  const std::string out = dir.file("half.json");
  const auto r = run_command(with_cache() + contactlab_exe() + " emulate threads" + kScene +
                             " --variants particle/sorted/half/static --threads 1,4"
                             " --measured-threads 1,2 --rounds 1 --chunk-threads 2 --json " +
                             out);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const json v = json::parse(slurp(out))["variants"][0];
  EXPECT_NEAR(v["emulated"][0]["detect_s"].get<double>(),
              v["measured"][0]["detect_s"]["median"].get<double>(), 1e-12);
  for (const auto& p : v["emulated"]) EXPECT_EQ(p["output_s"].get<double>(), 0.0) << p;
}

// Under chunks the half stencil's threads pass their reverse entries on to the rows' owners:
// its assembly is fitted as work / P + exchange (P - 1) / P^2 through its 1- and 2-thread times
// (ExchangePhase), the block deal's as serial + parallel / P (AmdahlPhase).
TEST(EmulateCli, TheHalfStencilsChunksPassTheirReverseEntriesOn) {
  TempDir dir;
  const std::string out = dir.file("half.json");
  const auto r = run_command(
      with_cache() + contactlab_exe() + " emulate threads" + kScene +
      " --variants particle/sorted/half/static,64,particle/sorted/half/static --threads 1,2,4,16"
      " --measured-threads 1,2 --rounds 1 --chunk-threads 2 --json " +
      out);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const json doc = json::parse(slurp(out));
  for (const bool chunked : {true, false}) {
    const json& points = doc["variants"][chunked ? 0 : 1]["emulated"];
    ASSERT_EQ(points.size(), 4u);
    const double one = points[0]["assembly_s"].get<double>();
    const double two = points[1]["assembly_s"].get<double>();
    for (const auto& p : points) {
      const double threads = p["threads"].get<double>();
      const double expected = chunked
                                  ? ExchangePhase::fit(one, 2, two).at(static_cast<int>(threads))
                                  : AmdahlPhase::fit(one, 2, two).at(static_cast<int>(threads));
      EXPECT_NEAR(p["assembly_s"].get<double>(), expected, 1e-12 + 1e-9 * expected)
          << (chunked ? "static,64 " : "static ") << p;
    }
  }
  EXPECT_NE(doc["method"].get<std::string>().find("work/P + exchange (P-1)/P^2"),
            std::string::npos);
}

TEST(EmulateCli, MpiPredictsEverySeriesAndChecksAMeasuredRun) {
  TempDir dir;
  const std::string measured = dir.file("detect.json"), out = dir.file("mpi.json");
  const auto detect =
      run_command(mpi_session_environment() + contactlab_exe() + " detect" + kScene +
                  " --variant particle/sorted/full/static,200 --threads 1"
                  " --mpi replicated --json " +
                  measured);
  if (detect.exit_code == 2 && detect.output.find("built without MPI") != std::string::npos) {
    GTEST_SKIP() << "this contactlab was built without MPI: no measured run to check against";
  }
  ASSERT_EQ(detect.exit_code, 0) << detect.output;
  const auto r = run_command(with_cache() + contactlab_exe() + " emulate mpi" + kScene +
                             " --processes 1,2,16,64 --threads-per-rank 16 --rounds 3"
                             " --measured " +
                             measured + " --json " + out);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const json doc = json::parse(slurp(out));
  EXPECT_EQ(doc["kind"], "contactlab-mpi-model");
  EXPECT_EQ(doc["label"], "predicted");
  ASSERT_EQ(doc["series"].size(), 3u);
  for (const auto& s : doc["series"]) {
    ASSERT_EQ(s["points"].size(), 4u);
    EXPECT_DOUBLE_EQ(s["points"][0]["speedup"].get<double>(), 1.0);
    for (const auto& p : s["points"]) {
      EXPECT_NEAR(p["efficiency"].get<double>(),
                  p["speedup"].get<double>() / p["processes"].get<double>(), 1e-12);
      EXPECT_NEAR(p["detect_s"].get<double>(),
                  p["compute_s"].get<double>() + p["communication_s"].get<double>(), 1e-15);
    }
  }
  EXPECT_EQ(doc["series"][1]["points"][3]["ranks"], 4);  // 64 processes: 4 ranks of 16
  // The measured run, then the pure series' slowest rank timed alone at each process count.
  ASSERT_EQ(doc["validation"].size(), 5u);
  EXPECT_EQ(doc["validation"][0]["mode"], "replicated");
  EXPECT_EQ(doc["validation"][0]["ranks"], 1);
  EXPECT_FALSE(doc["validation"][0]["oversubscribed"].get<bool>());
  for (std::size_t i = 1; i < 5; ++i) {
    EXPECT_EQ(doc["validation"][i]["mode"], "replicated, slowest rank alone");
  }
  for (const auto& p : doc["series"][0]["points"]) {
    const auto& alone = p["slowest_rank_measured_s"];
    EXPECT_LE(alone["low"].get<double>(), alone["median"].get<double>());
    EXPECT_LT(p["slowest_rank"].get<int>(), p["ranks"].get<int>());
  }
  EXPECT_FALSE(doc["series"][1]["points"][0].contains("slowest_rank_measured_s"));
  // Above one process the pure series' compute is its slowest rank's share timed alone: the
  // replay times the locality factor that measurement gives. The hybrid series deals its
  // threads every 64th block at 64 processes too, and takes the same factor.
  const auto& pure = doc["series"][0]["points"];
  EXPECT_EQ(pure[0]["locality_factor"].get<double>(), 1.0);
  for (std::size_t i = 1; i < 4; ++i) {
    EXPECT_GT(pure[i]["locality_factor"].get<double>(), 0.0);
    EXPECT_NEAR(pure[i]["compute_s"].get<double>(),
                pure[i]["slowest_rank_measured_s"]["median"].get<double>(),
                1e-9 * pure[i]["compute_s"].get<double>());
  }
  EXPECT_DOUBLE_EQ(doc["series"][1]["points"][3]["locality_factor"].get<double>(),
                   pure[3]["locality_factor"].get<double>());
}

TEST(EmulateCli, BadInputIsOneLineAndKeepsTheOutput) {
  TempDir dir;
  const std::string out = dir.file("kept.json");
  std::ofstream(out) << "{\"kept\": true}\n";
  const std::pair<const char*, const char*> cases[] = {
      {" emulate threads --measured-threads 2,4", "must start with 1"},
      {" emulate threads --threads 0,2", "--threads: '0'"},
      {" emulate threads --variants particle/sorted/ful/static", "ful"},
      {" emulate mpi --measured /nonexistent/d.json", "/nonexistent/d.json"},
      {" emulate mpi --block 0", "--block"},
      {" emulate threads --bandwidth-ceiling 100", "give --machine"},
      {" emulate threads --machine /nonexistent/m.json", "/nonexistent/m.json"},
  };
  for (const auto& [arguments, message] : cases) {
    const auto r =
        run_command(with_cache() + contactlab_exe() + arguments + kScene + " --json " + out);
    EXPECT_EQ(r.exit_code, 2) << arguments << "\n" << r.output;
    EXPECT_NE(r.output.find(message), std::string::npos) << arguments << "\n" << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
    EXPECT_EQ(slurp(out), "{\"kept\": true}\n");
  }
}

// --json in folders that do not exist yet: made (as mkdir -p); under a file, one line before
// anything is timed.
TEST(EmulateCli, JsonMakesItsFolders) {
  TempDir dir;
  const std::string blocker = dir.file("blocker");
  const std::string commands[] = {
      " emulate threads --scene uniform --n 2000 -D 0.05 --variants particle/sorted/full/static"
      " --threads 1,4 --measured-threads 1 --chunk-threads 4 --rounds 1",
      " emulate mpi --scene uniform --n 2000 -D 0.05 --processes 1,4 --threads-per-rank 1"
      " --rounds 1 --no-slowest-rank"};
  for (const std::string& command : commands) {
    const std::string out = dir.file("new/a/b/e.json");
    const auto r = run_command(with_cache() + contactlab_exe() + command + " --json " + out);
    ASSERT_EQ(r.exit_code, 0) << command << "\n" << r.output;
    EXPECT_TRUE(json::parse(slurp(out)).contains("kind")) << command;
    std::filesystem::remove_all(dir.file("new"));
    expect_blocked(run_command(with_cache() + contactlab_exe() + command + " --json " +
                               path_under_a_file(blocker, "e.json")),
                   blocker);
  }
}

}  // namespace
}  // namespace contactlab::test
