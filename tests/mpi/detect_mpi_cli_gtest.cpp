// `contactlab detect --mpi` end to end under mpiexec: the contacts file equals the serial run's,
// the result file reads back strictly with one record per rank, and errors (a bad particle in
// one rank's share, a bad option on every rank) end all ranks quickly with one message and no
// output left behind.
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "contactlab/kernels/scene_generate.hpp"
#include "contactlab/kernels/scene_io.hpp"
#include "contactlab/tuner/result_schema.hpp"
#include "mpi_cli_support.hpp"
#include "program_test_support.hpp"

namespace contactlab::test {
namespace {

std::vector<std::string> entries(const std::string& dir) {
  std::vector<std::string> names;
  for (const auto& e : std::filesystem::directory_iterator(dir))
    names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

TEST(DetectMpi, DecomposedFromABinaryFileWritesTheSerialContactsAndARecordPerRank) {
  TempDir dir;
  const std::string scene = dir.file("scene.bin");
  write_binary_scene(generate_scene(small_clustered(6000)), scene);
  const std::string exe = contactlab_exe();
  const auto serial = run_command(exe + " detect --input " + scene +
                                  " -D 0.02 --threads 1 --repeat 1 --warmup 0 --contacts-out " +
                                  dir.file("serial.csv"));
  ASSERT_EQ(serial.exit_code, 0) << serial.output;
  const auto mpi = run_command(mpiexec(3) + exe + " detect --input " + scene +
                               " -D 0.02 --threads 1 --mpi decomposed --contacts-out " +
                               dir.file("mpi.csv") + " --json " + dir.file("d.json"));
  ASSERT_EQ(mpi.exit_code, 0) << mpi.output;
  EXPECT_EQ(slurp(dir.file("mpi.csv")), slurp(dir.file("serial.csv")));
  const tuner::ResultFile result = tuner::read_result_file(dir.file("d.json"));
  ASSERT_EQ(result.runs.size(), 1u);
  ASSERT_TRUE(result.runs[0].mpi.has_value());
  const tuner::MpiRecord& m = *result.runs[0].mpi;
  EXPECT_EQ(m.mode, "decomposed");
  EXPECT_EQ(m.ranks, 3);
  ASSERT_EQ(m.per_rank.size(), 3u);
  std::uint64_t owned = 0;
  for (const auto& r : m.per_rank) {
    owned += r.owned_particles;
    EXPECT_LT(r.owned_particles, 6000u) << "a rank holds every particle";
    EXPECT_GT(r.peak_rss_bytes, 0u);
  }
  EXPECT_EQ(owned, 6000u);
  EXPECT_EQ(count_of(mpi.output, "max over ranks"), 1) << mpi.output;
}

TEST(DetectMpi, ReplicatedHybridWritesTheSerialContacts) {
  TempDir dir;
  const std::string exe = contactlab_exe();
  const std::string scene = " --scene clustered --n 5000 -D 0.02 --seed 3 ";
  const auto serial =
      run_command(exe + " detect" + scene + "--threads 1 --repeat 1 --warmup 0 --contacts-out " +
                  dir.file("serial.csv"));
  ASSERT_EQ(serial.exit_code, 0) << serial.output;
  const auto mpi = run_command(mpiexec(2) + exe + " detect" + scene +
                               "--threads 2 --mpi replicated --block 50 --contacts-out " +
                               dir.file("mpi.csv") + " --json " + dir.file("r.json"));
  ASSERT_EQ(mpi.exit_code, 0) << mpi.output;
  EXPECT_EQ(slurp(dir.file("mpi.csv")), slurp(dir.file("serial.csv")));
  const tuner::ResultFile result = tuner::read_result_file(dir.file("r.json"));
  ASSERT_TRUE(result.runs.at(0).mpi.has_value());
  EXPECT_EQ(result.runs[0].mpi->block, 50u);
  EXPECT_EQ(result.runs[0].parameters.threads, 2);
}

// The last particle (in the last rank's share only) lies outside the box: every rank must end,
// non-zero, within seconds, with one error line, and no contacts file or temporary left.
TEST(DetectMpi, ABadParticleSeenByOneRankEndsEveryRankWithOneMessage) {
  TempDir dir;
  Scene scene = generate_scene(small_clustered(3000));
  scene.x.back() = 1.5;
  const std::string path = dir.file("bad.bin");
  write_binary_scene(scene, path);  // the writer does not validate; readers do
  const auto start = std::chrono::steady_clock::now();
  const auto run = run_command(mpiexec(3) + contactlab_exe() + " detect --input " + path +
                               " -D 0.02 --threads 1 --mpi decomposed --contacts-out " +
                               dir.file("pairs.csv") + " --json " + dir.file("d.json"));
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_NE(run.exit_code, 0) << run.output;
  EXPECT_LT(seconds, 30.0);
  EXPECT_EQ(count_of(run.output, "contactlab: error:"), 1) << run.output;
  EXPECT_NE(run.output.find("particle 2999"), std::string::npos) << run.output;
  EXPECT_EQ(entries(std::filesystem::path(path).parent_path().string()),
            std::vector<std::string>{"bad.bin"});
}

TEST(DetectMpi, ABadOptionOnEveryRankGivesOneMessage) {
  for (const std::string options :
       {"--mpi sideways", "--mpi decomposed --adaptive", "--mpi decomposed --halo 0.001",
        "--mpi replicated --block 0"}) {
    const auto run = run_command(mpiexec(2) + contactlab_exe() +
                                 " detect --scene uniform --n 500 -D 0.02 --threads 1 " + options);
    EXPECT_NE(run.exit_code, 0) << options << ": " << run.output;
    EXPECT_EQ(count_of(run.output, "contactlab: error:"), 1) << options << ": " << run.output;
  }
}

// --contacts-out and --json in folders that do not exist yet: rank 0 makes them before the
// detection (the other ranks write the contacts file's shares into the folder it made); under
// a file, every rank ends with one message.
TEST(DetectMpi, OutputsMakeTheirFolders) {
  TempDir dir;
  const std::string detect = mpiexec(2) + contactlab_exe() +
                             " detect --scene clustered --n 3000 -D 0.03 --threads 1"
                             " --mpi decomposed --repeat 1 --warmup 0";
  const std::string csv = dir.file("new/a/b/pairs.csv"), json = dir.file("new/c/d/r.json");
  const auto run = run_command(detect + " --contacts-out " + csv + " --json " + json);
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_EQ(slurp(csv).rfind("i,j\n", 0), 0u);
  EXPECT_EQ(tuner::read_result_file(json).runs.size(), 1u);
  const std::string blocker = dir.file("blocker");
  for (const char* option : {" --contacts-out ", " --json "}) {
    const auto blocked = run_command(detect + option + path_under_a_file(blocker, "x"));
    EXPECT_NE(blocked.exit_code, 0) << option << blocked.output;
    EXPECT_EQ(count_of(blocked.output, "contactlab: error:"), 1) << option << blocked.output;
    EXPECT_NE(blocked.output.find("'" + blocker + "' is a file, not a folder"), std::string::npos)
        << option << blocked.output;
    EXPECT_EQ(slurp(blocker), kInTheWay);
  }
}

// --repeat and --warmup: one sample per timed repetition, each its slowest rank's, and the
// repetition settings in the record.
TEST(DetectMpi, RepetitionsAreEachTheSlowestRanks) {
  TempDir dir;
  const std::string json = dir.file("r.json");
  const auto run = run_command(mpiexec(2) + contactlab_exe() +
                               " detect --scene clustered --n 3000 -D 0.03 --threads 1"
                               " --mpi replicated --warmup 1 --repeat 3 --json " +
                               json);
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const tuner::ResultFile file = tuner::read_result_file(json);
  ASSERT_EQ(file.runs.size(), 1u);
  const tuner::RunRecord& record = file.runs.front();
  EXPECT_EQ(record.parameters.repetition.repeat, 3);
  EXPECT_EQ(record.parameters.repetition.warmup, 1);
  ASSERT_EQ(record.samples.detect_s.size(), 3u);
  ASSERT_TRUE(record.aggregates.has_value());
  EXPECT_EQ(record.aggregates->repetitions, 3);
  ASSERT_TRUE(record.mpi.has_value());
  // Each rank's reported T_c is its median: none exceeds the largest repetition's maximum.
  double largest = 0;
  for (const double s : record.samples.detect_s) largest = std::max(largest, s);
  for (const auto& rank : record.mpi->per_rank) EXPECT_LE(rank.detection_s, largest);
}

// Without mpiexec (a singleton MPI process) --mpi works on one rank.
TEST(DetectMpi, RunsWithoutMpiexecAsOneRank) {
  const auto run =
      run_command(std::string(CONTACTLAB_MPI_ENV) + " " + mpi_session_environment() +
                  contactlab_exe() + " detect --scene uniform --n 2000 -D 0.03 --mpi decomposed");
  EXPECT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find("ranks 1"), std::string::npos) << run.output;
}

}  // namespace
}  // namespace contactlab::test
