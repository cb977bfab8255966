// `contactlab dem` end to end: frames and energy CSV, a restart that reproduces the
// uninterrupted run's frames bit for bit, bad configs without output, validate's exit code.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "program_test_support.hpp"

namespace contactlab::test {
namespace {

namespace fs = std::filesystem;

// The folder itself (TempDir hands out files in it).
fs::path root(const TempDir& dir) { return fs::path(dir.file("x")).parent_path(); }

std::string config_path() {
  return std::string(CONTACTLAB_SOURCE_DIR) + "/experiments/dem/drop-box.json";
}

// The drop-box config with another end time, written to `dir`.
std::string config_ending_at(const TempDir& dir, const std::string& end) {
  std::string text = slurp(config_path());
  const std::string key = "\"end\": 0.004";
  const auto at = text.find(key);
  EXPECT_NE(at, std::string::npos);
  text.replace(at, key.size(), "\"end\": " + end);
  const std::string path = dir.file("drop-" + end + ".json");
  std::ofstream(path) << text;
  return path;
}

TEST(DemCli, RunWritesFramesSeriesAndEnergy) {
  TempDir dir;
  const auto r = run_command(contactlab_exe() + " dem run " + config_path() +
                             " --threads 2 --vtk " + root(dir).string() + "/");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(fs::exists(root(dir) / "drop.pvd"));
  for (int f = 0; f <= 4; ++f) {
    const std::string frame = slurp(root(dir) / ("drop_0000" + std::to_string(f) + ".vtp"));
    for (const char* field : {"\"id\"", "\"radius\"", "\"velocity\"", "\"angular_velocity\"",
                              "\"contacts\"", "\"force_magnitude\""}) {
      EXPECT_NE(frame.find(field), std::string::npos) << field;
    }
  }
  const std::string csv = slurp(root(dir) / "drop_energy.csv");
  EXPECT_EQ(csv.rfind("time_s,step,kinetic_J,potential_J,dissipated_J\n", 0), 0u);
  EXPECT_TRUE(fs::exists(root(dir) / "last.chk"));
}

TEST(DemCli, RestartReproducesTheUninterruptedFrames) {
  TempDir whole_dir, split_dir;
  const auto whole = run_command(contactlab_exe() + " dem run " + config_path() +
                                 " --threads 1 --vtk " + root(whole_dir).string());
  ASSERT_EQ(whole.exit_code, 0) << whole.output;
  // First half (to 0.002 s) on 2 threads, then the rest from its checkpoint.
  const std::string half = config_ending_at(split_dir, "0.002");
  const auto first = run_command(contactlab_exe() + " dem run " + half + " --threads 2 --vtk " +
                                 root(split_dir).string());
  ASSERT_EQ(first.exit_code, 0) << first.output;
  const auto second =
      run_command(contactlab_exe() + " dem run " + config_path() + " --threads 2 --vtk " +
                  root(split_dir).string() + " --restart " + split_dir.file("last.chk"));
  ASSERT_EQ(second.exit_code, 0) << second.output;
  for (int f = 0; f <= 4; ++f) {
    const std::string name = "drop_0000" + std::to_string(f) + ".vtp";
    EXPECT_EQ(slurp(root(whole_dir) / name), slurp(root(split_dir) / name)) << name;
  }
  EXPECT_EQ(slurp(root(whole_dir) / "drop.pvd"), slurp(root(split_dir) / "drop.pvd"));
  EXPECT_EQ(slurp(root(whole_dir) / "drop_energy.csv"), slurp(root(split_dir) / "drop_energy.csv"));
}

TEST(DemCli, BadConfigIsOneLineAndNoOutput) {
  TempDir dir;
  const std::string path = dir.file("bad.json");
  std::string text = slurp(config_path());
  text.replace(text.find("\"restitution\": 0.7"), 18, "\"restitution\": 1.5");
  std::ofstream(path) << text;
  const fs::path out = root(dir) / "out";
  fs::create_directory(out);
  const auto r = run_command(contactlab_exe() + " dem run " + path + " --vtk " + out.string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("$.contact.restitution"), std::string::npos) << r.output;
  EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
  EXPECT_TRUE(fs::is_empty(out));
}

TEST(DemCli, ValidateStabilityCasePrintsTheTable) {
  const auto r = run_command(contactlab_exe() + " dem validate --case stability");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("stable limit"), std::string::npos);
  EXPECT_NE(r.output.find("pass"), std::string::npos);
}

TEST(DemCli, TimestepPrintsLimitAndTable) {
  const auto r =
      run_command(contactlab_exe() + " dem timestep " + config_path() + " --steps 20 --threads 1");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("stable limit"), std::string::npos);
  EXPECT_NE(r.output.find("t_c/200"), std::string::npos);
}

// Every validation case also passes on the report's variant (per-thread arrays, dynamic
// schedule, serial walls) at two threads.
TEST(DemCli, ValidatePassesOnTheReportsVariant) {
  const auto r = run_command(contactlab_exe() +
                             " dem validate --variant per-thread/dynamic,1/walls=serial/"
                             "update=separate --threads 2");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("All cases pass."), std::string::npos) << r.output;
}

TEST(DemCli, VariantsTablesSpeedAgainstTheDefault) {
  const auto r = run_command(contactlab_exe() + " dem variants " + config_path() +
                             " --steps 20 --threads 1,2 --variant atomic/dynamic,8"
                             " --variant ordered/static/update=separate");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("atomic/dynamic,8"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("bit-identical"), std::string::npos) << r.output;
  const auto bad = run_command(contactlab_exe() + " dem variants " + config_path() +
                               " --variant ordered/dynamic,4");
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find("static block partition"), std::string::npos) << bad.output;
}

}  // namespace
}  // namespace contactlab::test
