// `contactlab dem` end to end: frames and energy CSV, a restart that reproduces the
// uninterrupted run's frames bit for bit, bad configs without output, validate's exit code, a
// hopper's discharge series, --steps, and its PNG pictures; every output option's folders made
// when missing (as mkdir -p), and a folder that cannot be made one line at the start.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "contactlab/dem/engine.hpp"
#include "dem_configs.hpp"
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
  std::string path = dir.file("drop-" + end + ".json");
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
  // The instruction set the step ran on, named on the done line.
  EXPECT_NE(r.output.find(", step on " + dem::to_string(dem::step_isa()) + "\n"), std::string::npos)
      << r.output;
}

// The step on the set CONTACTLAB_SIMD asks for (below AVX2: the baseline), and said so.
TEST(DemCli, RunNamesTheInstructionSetItWasToldToUse) {
  const auto r = run_command("CONTACTLAB_SIMD=off " + contactlab_exe() + " dem run " +
                             config_path() + " --steps 20");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find(", step on baseline\n"), std::string::npos) << r.output;
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

TEST(DemCli, HopperWritesDischargeSeriesAndStopsAfterSteps) {
  TempDir dir;
  const std::string config = tiny_hopper(dir);
  const auto r = run_command(contactlab_exe() + " dem run " + config +
                             " --threads 1 --steps 1000 --vtk " + root(dir).string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("steps 0 -> 1000"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("sink below z = -0.002 m"), std::string::npos) << r.output;
  const std::string csv = slurp(root(dir) / "tiny_discharge.csv");
  EXPECT_EQ(csv.rfind("time_s,step,discharged_kg,discharged_particles,particles_left\n", 0), 0u);
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 4) << csv;  // header, t = 0, 1 and 2 ms
  // --steps N continues from the checkpoint by N more steps; the series goes on.
  const auto more =
      run_command(contactlab_exe() + " dem run " + config + " --threads 1 --steps 500 --vtk " +
                  root(dir).string() + " --restart " + dir.file("last.chk"));
  ASSERT_EQ(more.exit_code, 0) << more.output;
  EXPECT_NE(more.output.find("steps 1000 -> 1500"), std::string::npos) << more.output;
  const std::string longer = slurp(root(dir) / "tiny_discharge.csv");
  EXPECT_EQ(longer.rfind(csv, 0), 0u);
  EXPECT_EQ(std::count(longer.begin(), longer.end(), '\n'), 5) << longer;
}

TEST(DemCli, RunStopsWhenEveryParticleHasLeft) {
  TempDir dir;
  const std::string config = tiny_hopper_with_sink(dir, "1.0");  // above every particle
  const auto r = run_command(contactlab_exe() + " dem run " + config + " --threads 1 --discharge " +
                             dir.file("d.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("every particle has left through the sink"), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("150 particles, 0 left"), std::string::npos) << r.output;
  const std::string csv = slurp(dir.file("d.csv"));
  EXPECT_NE(csv.find(",150,0\n"), std::string::npos) << csv;
}

// --until-discharged F: the run stops at the first step (a neighbour-list rebuild: the sink's
// step) by which the sink has taken F of the mass, writes its last row and checkpoint, exit 0.
TEST(DemCli, RunStopsWhenTheSinkHasTakenTheFraction) {
  TempDir dir;
  const std::string config = tiny_hopper_with_sink(dir, "0.002");  // the bottom layers
  const auto r = run_command(contactlab_exe() + " dem run " + config + " --threads 2 --discharge " +
                             dir.file("d.csv") + " --checkpoint " + dir.file("c.chk") +
                             " --until-discharged 0.5");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto at = r.output.find("the sink has taken ");
  ASSERT_NE(at, std::string::npos) << r.output;
  double taken = 0, total = 0;
  ASSERT_EQ(
      std::sscanf(r.output.c_str() + at, "the sink has taken %lf kg of %lf kg", &taken, &total), 2)
      << r.output;
  EXPECT_GE(taken, 0.5 * total);
  EXPECT_LT(taken, total);
  EXPECT_TRUE(fs::exists(dir.file("c.chk")));
  // The discharge series ends on the stopping step, with the mass the message gives.
  const std::string csv = slurp(dir.file("d.csv"));
  const std::string last = csv.substr(csv.rfind('\n', csv.size() - 2) + 1);
  double time_s = 0, last_kg = 0;
  long step = 0;
  ASSERT_EQ(std::sscanf(last.c_str(), "%lf,%ld,%lf", &time_s, &step, &last_kg), 3) << csv;
  EXPECT_GT(step, 0);
  EXPECT_NEAR(last_kg, taken, 1e-5 * taken) << csv;
}

TEST(DemCli, PngSectionsAndDischargePlot) {
  TempDir dir;
  const auto r = run_command(contactlab_exe() + " dem run " + tiny_hopper(dir) +
                             " --threads 1 --steps 600 --png " + root(dir).string());
#ifdef CONTACTLAB_HAVE_CAIRO
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* file : {"tiny_section_00000.png", "tiny_section_00001.png", "tiny_discharge.png",
                           "tiny_discharge.csv"}) {
    EXPECT_TRUE(fs::exists(root(dir) / file)) << file;
  }
  EXPECT_EQ(slurp(root(dir) / "tiny_section_00001.png").rfind("\x89PNG\r\n\x1a\n", 0), 0u);
#else
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("built without cairo"), std::string::npos) << r.output;
#endif
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
  const auto r = run_command(
      contactlab_exe() + " dem validate --variant per-thread/dynamic,1/walls=serial --threads 2");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("All cases pass."), std::string::npos) << r.output;
}

TEST(DemCli, VariantsTablesSpeedAgainstTheDefault) {
  const auto r = run_command(contactlab_exe() + " dem variants " + config_path() +
                             " --steps 20 --threads 1,2 --variant atomic/dynamic,8"
                             " --variant ordered/static/update=fused");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("atomic/dynamic,8"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("bit-identical"), std::string::npos) << r.output;
  const auto bad = run_command(contactlab_exe() + " dem variants " + config_path() +
                               " --variant ordered/dynamic,4");
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find("static block partition"), std::string::npos) << bad.output;
}

TEST(DemCli, ProfilePrintsPhasesSerialFractionAndAmdahl) {
  const auto r =
      run_command(contactlab_exe() + " dem profile " + config_path() + " --steps 20 --threads 1,2");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  for (const char* line : {"candidates (neighbour list)", "pair forces", "serial fraction",
                           "Amdahl bound at 2 / 8 / 16 threads", "Karp-Flatt"}) {
    EXPECT_NE(r.output.find(line), std::string::npos) << line << "\n" << r.output;
  }
  const auto bad = run_command(contactlab_exe() + " dem profile " + config_path() + " --threads 2");
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find("must start with 1"), std::string::npos) << bad.output;
}

// dem profile --json with --emulate: measured rounds with intervals, the emulated thread counts
// (the measured ones included, 1 the anchor), and the check at the measured 2 threads.
TEST(DemCli, ProfileJsonHasMeasuredEmulatedAndTheCheck) {
  TempDir dir;
  const std::string out = dir.file("profile.json");
  const auto r = run_command(contactlab_exe() + " dem profile " + config_path() +
                             " --steps 10 --threads 1,2 --rounds 3 --emulate 4,8 --json " + out);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json doc = nlohmann::json::parse(slurp(out));
  EXPECT_EQ(doc["kind"], "contactlab-dem-profile");
  EXPECT_EQ(doc["rounds"], 3);
  ASSERT_EQ(doc["measured"].size(), 2u);
  for (const auto& m : doc["measured"]) {
    EXPECT_LE(m["step_s"]["low"].get<double>(), m["step_s"]["median"].get<double>());
    EXPECT_LE(m["step_s"]["median"].get<double>(), m["step_s"]["high"].get<double>());
    EXPECT_EQ(m["step_s"]["repetitions"], 3);
    // Each round's own speed-up: its one-thread step over this one, 1 at one thread.
    ASSERT_EQ(m["round_step_s"].size(), 3u);
    ASSERT_EQ(m["round_speedups"].size(), 3u);
    for (std::size_t k = 0; k < 3; ++k) {
      EXPECT_DOUBLE_EQ(
          m["round_speedups"][k].get<double>(),
          doc["measured"][0]["round_step_s"][k].get<double>() / m["round_step_s"][k].get<double>());
    }
  }
  std::vector<int> emulated;
  for (const auto& e : doc["emulated"]) emulated.push_back(e["threads"].get<int>());
  EXPECT_EQ(emulated, (std::vector<int>{1, 2, 4, 8}));
  EXPECT_DOUBLE_EQ(doc["emulated"][0]["speedup"].get<double>(), 1.0);
  ASSERT_EQ(doc["validation"].size(), 1u);
  const auto& check = doc["validation"][0];
  EXPECT_EQ(check["threads"], 2);
  EXPECT_NEAR(check["relative_error"].get<double>(),
              check["emulated_step_s"].get<double>() / check["measured_step_s"].get<double>() - 1,
              1e-12);
  for (const char* phase : {"candidates_s", "pair_forces_s", "update_s", "integration_s"}) {
    EXPECT_TRUE(doc["phase_split"].contains(phase)) << phase;
  }
  // The serial fraction: the list's serial part fitted from 1 and 2 threads is at most the whole
  // list (the upper bound it replaced); counted whole, it is that bound; without a rebuild, the
  // serial walls alone.
  double total = 0.0;
  for (const auto& [phase, seconds] : doc["phase_split"].items()) total += seconds.get<double>();
  const auto& split = doc["phase_split"];
  const double whole =
      (split["candidates_s"].get<double>() + split["wall_forces_s"].get<double>()) / total;
  const std::string method = doc["serial_fraction_method"];
  const double serial = doc["serial_fraction"];
  if (method.find("fitted from 1 and 2 threads") != std::string::npos) {
    EXPECT_LE(serial, whole * (1 + 1e-12)) << method;
  } else if (method.find("counted whole") != std::string::npos) {
    EXPECT_NEAR(serial, whole, 1e-12 * whole) << method;
  } else {
    EXPECT_EQ(method, "no neighbour-list rebuild in the timed steps");
    EXPECT_NEAR(serial, split["wall_forces_s"].get<double>() / total, 1e-12) << method;
  }
  const auto bad =
      run_command(contactlab_exe() + " dem profile " + config_path() + " --rounds 0 --json " + out);
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find("--rounds"), std::string::npos) << bad.output;
  EXPECT_EQ(nlohmann::json::parse(slurp(out))["rounds"], 3);  // the earlier file is kept
}

// tune --dem: the model (calibrated, then every candidate priced), the search over its best
// and the exhaustive sweep, each choice verified beside the default and the report's.
TEST(DemCli, TuneDemRunsModelSearchAndExhaustive) {
  TempDir dir;
  const std::string report = dir.file("tune-dem.json");
  const auto r =
      run_command(contactlab_exe() + " tune --dem " + config_path() +
                  " --threads 2 --dem-steps 5 --exhaustive --verify-rounds 2 --json " + report);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  for (const char* line : {"calibrated by 12 runs", "model ", "search ", "exhaustive ", "default ",
                           "report's ", "chosen", "model err"}) {
    EXPECT_NE(r.output.find(line), std::string::npos) << line << "\n" << r.output;
  }
  const std::string json = slurp(report);
  for (const char* key : {"\"kind\": \"dem_force_variant_tuning\"", "\"calibration\"",
                          "\"seconds_per_foreign_j_side\"", "\"predictions\"", "\"model_error\"",
                          "full-list/dynamic,16", "per-thread/dynamic,16"}) {
    EXPECT_NE(json.find(key), std::string::npos) << key << "\n" << json;
  }
  // --predict-only: the model alone, nothing timed but its calibration.
  const auto model = run_command(contactlab_exe() + " tune --dem " + config_path() +
                                 " --threads 1 --dem-steps 5 --predict-only");
  EXPECT_EQ(model.exit_code, 0) << model.output;
  EXPECT_NE(model.output.find("predicted only"), std::string::npos) << model.output;
  EXPECT_EQ(model.output.find("search "), std::string::npos) << model.output;
}

// `dem run --variant auto --retune` of the drop box with `flags` added: its output, and its
// variant log (CSV) in `log`.
CommandResult run_retuned(const std::string& flags, const std::string& log) {
  return run_command(contactlab_exe() + " dem run " + config_path() +
                     " --threads 2 --variant auto --retune --calibration-steps 5 " + flags +
                     " --variant-log " + log);
}

// dem run --variant auto --retune: the model's choice at the start and at every rebuild, the
// log of which variant ran when; --retune alone is refused.
TEST(DemCli, RunRetunesAtRebuildsAndLogsTheVariants) {
  TempDir dir;
  const std::string log = dir.file("variants.csv");
  const auto r = run_retuned("--steps 300", log);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("variant auto: force model calibrated by 12 runs"), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("variant auto: starts with"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("variants ran"), std::string::npos) << r.output;
  const std::string csv = slurp(log);
  EXPECT_EQ(csv.rfind("begin_step,end_step,time_s,variant,predicted_gain\n0,", 0), 0u) << csv;
  const auto bad = run_command(contactlab_exe() + " dem run " + config_path() + " --retune");
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find("--retune needs --variant auto"), std::string::npos) << bad.output;
}

// The start leaves the config's variant only for a predicted gain above the margin, as every
// later switch does: with a margin no prediction reaches, the run keeps the default throughout.
TEST(DemCli, AutoVariantKeepsTheDefaultWithinTheMargin) {
  TempDir dir;
  const std::string log = dir.file("variants.csv");
  const auto r = run_retuned("--steps 100 --retune-margin 100", log);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("variant auto: starts with ordered/static (the model's best, "),
            std::string::npos)
      << r.output;
  const std::string csv = slurp(log);
  EXPECT_EQ(csv.find('\n', csv.find('\n') + 1) + 1, csv.size()) << "one variant ran: " << csv;
  EXPECT_NE(csv.find(",ordered/static,"), std::string::npos) << csv;
}

// ---------------------------------------------------------------------------------------------
// Output folders: each option writing files makes its missing folders (nested, as mkdir -p) at
// the start; one that cannot be made (a file in the way) stops the run there with one line.

TEST(DemCli, VtkMakesItsFolders) {
  TempDir dir;
  const fs::path out = root(dir) / "out/bed1";
  const auto r = run_command(contactlab_exe() + " dem run " + config_path() +
                             " --threads 1 --steps 50 --vtk " + out.string() + "/");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* file : {"drop.pvd", "drop_00000.vtp", "drop_energy.csv", "last.chk"}) {
    EXPECT_TRUE(fs::is_regular_file(out / file)) << file;
  }
}

TEST(DemCli, PngMakesItsFolders) {
  TempDir dir;
  const fs::path out = root(dir) / "new/a/b";
  const auto r = run_command(contactlab_exe() + " dem run " + tiny_hopper(dir) +
                             " --threads 1 --steps 100 --png " + out.string());
#ifdef CONTACTLAB_HAVE_CAIRO
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* file : {"tiny_section_00000.png", "tiny_discharge.png", "tiny_discharge.csv"}) {
    EXPECT_TRUE(fs::is_regular_file(out / file)) << file;
  }
#else
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("built without cairo"), std::string::npos) << r.output;
#endif
}

TEST(DemCli, DischargeMakesItsFolders) {
  TempDir dir;
  const std::string csv = dir.file("new/a/b/d.csv");
  const auto r = run_command(contactlab_exe() + " dem run " + tiny_hopper(dir) +
                             " --threads 1 --steps 100 --discharge " + csv);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(slurp(csv).rfind("time_s,step,discharged_kg,", 0), 0u);
}

TEST(DemCli, CheckpointMakesItsFolders) {
  TempDir dir;
  const std::string chk = dir.file("new/a/b/c.chk");
  const auto r = run_command(contactlab_exe() + " dem run " + config_path() +
                             " --threads 1 --steps 50 --checkpoint " + chk);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(fs::is_regular_file(chk));
}

TEST(DemCli, VariantLogMakesItsFolders) {
  TempDir dir;
  const std::string log = dir.file("new/a/b/variants.csv");
  const auto r = run_retuned("--steps 50", log);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(slurp(log).rfind("begin_step,end_step,time_s,variant,predicted_gain\n", 0), 0u);
}

TEST(DemCli, ProfileJsonMakesItsFolders) {
  TempDir dir;
  const std::string profile =
      contactlab_exe() + " dem profile " + config_path() + " --steps 5 --threads 1 --rounds 1";
  const std::string out = dir.file("new/a/b/profile.json");
  const auto r = run_command(profile + " --json " + out);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(nlohmann::json::parse(slurp(out))["kind"], "contactlab-dem-profile");
  const std::string blocker = dir.file("blocker");
  expect_blocked(run_command(profile + " --json " + path_under_a_file(blocker, "p.json")), blocker);
}

TEST(DemCli, TuneDemJsonMakesItsFolders) {
  TempDir dir;
  const std::string tune = contactlab_exe() + " tune --dem " + config_path() +
                           " --threads 1 --dem-steps 5 --predict-only";
  const std::string out = dir.file("new/a/b/tune-dem.json");
  const auto r = run_command(tune + " --json " + out);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(slurp(out).find("\"kind\": \"dem_force_variant_tuning\""), std::string::npos);
  const std::string blocker = dir.file("blocker");
  expect_blocked(run_command(tune + " --json " + path_under_a_file(blocker, "t.json")), blocker);
}

// Every output option of `dem run` under a file: exit 2 and one line naming the file in the
// way, before any step (the issue's `--vtk out/bed1/` where `out` is a file among them); the
// outputs of an earlier run in the --vtk folder are kept as they were.
TEST(DemCli, RunOutputUnderAFileStopsAtTheStartAndKeepsEarlierOutput) {
  TempDir dir;
  const fs::path vtk = root(dir) / "vtk";
  const std::string run =
      contactlab_exe() + " dem run " + config_path() + " --threads 1 --steps 50";
  ASSERT_EQ(run_command(run + " --vtk " + vtk.string()).exit_code, 0);
  const std::string pvd = slurp(vtk / "drop.pvd"), chk = slurp(vtk / "last.chk");
  const std::string blocker = dir.file("out");
  const std::string under = path_under_a_file(blocker, "x");
  const std::string hopper = contactlab_exe() + " dem run " + tiny_hopper(dir) + " --threads 1";
  std::vector<std::string> commands = {run + " --vtk " + blocker + "/bed1/",
                                       run + " --vtk " + vtk.string() + " --checkpoint " + under,
                                       hopper + " --vtk " + vtk.string() + " --discharge " + under,
                                       run + " --variant auto --calibration-steps 5 --vtk " +
                                           vtk.string() + " --variant-log " + under};
#ifdef CONTACTLAB_HAVE_CAIRO
  commands.push_back(run + " --vtk " + vtk.string() + " --png " + under);
#endif
  for (const std::string& command : commands) {
    SCOPED_TRACE(command);
    expect_blocked(run_command(command), blocker);
    EXPECT_EQ(slurp(vtk / "drop.pvd"), pvd);
    EXPECT_EQ(slurp(vtk / "last.chk"), chk);
  }
}

}  // namespace
}  // namespace contactlab::test
