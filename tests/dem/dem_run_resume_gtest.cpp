// `dem run --resume`, `--until-time` and `--progress` end to end: a run stopped between outputs
// (by --until-time, or by SIGTERM as a batch system's time limit sends it) and continued by the
// same command writes the unbroken run's frames, series and energies byte for byte; the progress
// lines give the share, the simulated time, the rate and the time left; conflicting options are
// one line each.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>

#include "program_test_support.hpp"

namespace contactlab::test {
namespace {

namespace fs = std::filesystem;

fs::path root(const TempDir& dir) { return fs::path(dir.file("x")).parent_path(); }

// The drop box (216 spheres, output every 0.001 s) ending at `end` seconds, written to `dir`.
std::string drop_box_ending_at(const TempDir& dir, const std::string& end) {
  std::string text = slurp(std::string(CONTACTLAB_SOURCE_DIR) + "/experiments/dem/drop-box.json");
  const std::string key = "\"end\": 0.004";
  const auto at = text.find(key);
  EXPECT_NE(at, std::string::npos);
  text.replace(at, key.size(), "\"end\": " + end);
  std::string path = dir.file("drop.json");
  std::ofstream(path) << text;
  return path;
}

std::string frame_name(int frame) {
  const std::string number = std::to_string(frame);
  return "drop_" + std::string(5 - number.size(), '0') + number + ".vtp";
}

void expect_same_series(const fs::path& a, const fs::path& b, int frames) {
  for (int f = 0; f < frames; ++f) {
    ASSERT_TRUE(fs::exists(a / frame_name(f))) << frame_name(f);
    EXPECT_EQ(slurp(a / frame_name(f)), slurp(b / frame_name(f))) << frame_name(f);
  }
  EXPECT_FALSE(fs::exists(b / frame_name(frames)));
  EXPECT_EQ(slurp(a / "drop.pvd"), slurp(b / "drop.pvd"));
  EXPECT_EQ(slurp(a / "drop_energy.csv"), slurp(b / "drop_energy.csv"));
}

TEST(DemRunResume, StoppedBetweenOutputsTheSameCommandContinuesTheUnbrokenSeries) {
  TempDir whole_dir, split_dir;
  const std::string config = drop_box_ending_at(whole_dir, "0.004");
  const auto whole = run_command(contactlab_exe() + " dem run " + config + " --threads 2 --vtk " +
                                 (root(whole_dir) / "v").string());
  ASSERT_EQ(whole.exit_code, 0) << whole.output;
  // Stopped at 0.0025 s, between the outputs at 0.002 and 0.003 s, with a checkpoint after
  // every batch; then the same command without the stop.
  const std::string resume = split_dir.file("fill.chk");
  const std::string command = contactlab_exe() + " dem run " + config + " --threads 1 --vtk " +
                              (root(split_dir) / "v").string() + " --resume " + resume +
                              " --resume-every 1e-9";
  const auto first = run_command(command + " --until-time 0.0025");
  ASSERT_EQ(first.exit_code, 0) << first.output;
  EXPECT_EQ(first.output.find("resuming"), std::string::npos) << first.output;
  const auto second = run_command(command);
  ASSERT_EQ(second.exit_code, 0) << second.output;
  EXPECT_NE(second.output.find("resuming from " + resume + ": step 1250, t = 0.0025 s"),
            std::string::npos)
      << second.output;
  expect_same_series(root(whole_dir) / "v", root(split_dir) / "v", 5);
  // Run once more, it has nothing left to do and keeps what is written.
  const auto third = run_command(command);
  ASSERT_EQ(third.exit_code, 0) << third.output;
  expect_same_series(root(whole_dir) / "v", root(split_dir) / "v", 5);
}

TEST(DemRunResume, SigtermLeavesACheckpointThatTheSameCommandContinues) {
  TempDir whole_dir, split_dir;
  // 0.2 s of the drop box: 100,000 steps, seconds of work, so that the signal lands mid-run.
  const std::string config = drop_box_ending_at(whole_dir, "0.2");
  const std::string resume = split_dir.file("fill.chk");
  const std::string command = contactlab_exe() + " dem run " + config + " --threads 2 --vtk " +
                              (root(split_dir) / "v").string() + " --resume " + resume;
  const auto stopped = run_command("sh -c '" + command + " & pid=$!; sleep 0.5; kill -TERM $pid; " +
                                   "wait $pid; echo exit=$?'");
  ASSERT_NE(stopped.output.find("exit=143"), std::string::npos) << stopped.output;
  EXPECT_NE(stopped.output.find("contactlab: stopped by signal 15 at step "), std::string::npos)
      << stopped.output;
  EXPECT_NE(stopped.output.find(resume + " holds the run; the same command continues it"),
            std::string::npos)
      << stopped.output;
  const auto continued = run_command(command);
  ASSERT_EQ(continued.exit_code, 0) << continued.output;
  EXPECT_NE(continued.output.find("resuming from"), std::string::npos) << continued.output;
  const auto whole = run_command(contactlab_exe() + " dem run " + config + " --threads 2 --vtk " +
                                 (root(whole_dir) / "v").string());
  ASSERT_EQ(whole.exit_code, 0) << whole.output;
  expect_same_series(root(whole_dir) / "v", root(split_dir) / "v", 201);
}

TEST(DemRunResume, ProgressLinesGiveShareTimeRateAndTimeLeft) {
  TempDir dir;
  const std::string config = drop_box_ending_at(dir, "0.01");
  const auto r = run_command(contactlab_exe() + " dem run " + config + " --progress 1e-9");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("contactlab: dem run: 25 % after "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(" M particle-steps/s, about "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(", t = 0.00"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("contactlab: dem run: 100 %, done in "), std::string::npos) << r.output;
}

TEST(DemRunResume, ConflictingStopsAndCheckpointsAreOneLine) {
  TempDir dir;
  const std::string config = drop_box_ending_at(dir, "0.004");
  const std::string resume = dir.file("r.chk");
  const std::pair<std::string, std::string> cases[] = {
      {"--steps 10 --until-time 0.001", "--steps and --until-time: give one of them"},
      {"--until-time -1", "--until-time must be >= 0"},
      {"--resume " + resume + " --restart " + resume, "--resume and --restart: give one of them"},
      {"--resume " + resume + " --checkpoint " + dir.file("c.chk"),
       "--resume and --checkpoint: give one of them"},
      {"--resume " + resume + " --resume-every 0", "--resume-every must be > 0 seconds"},
      {"--progress -1", "--progress must be >= 0 seconds"}};
  for (const auto& [flags, message] : cases) {
    const auto r = run_command(contactlab_exe() + " dem run " + config + " " + flags);
    EXPECT_EQ(r.exit_code, 2) << flags << ": " << r.output;
    EXPECT_NE(r.output.find(message), std::string::npos) << flags << ": " << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << flags << ": " << r.output;
  }
  EXPECT_FALSE(fs::exists(resume));
}

}  // namespace
}  // namespace contactlab::test
