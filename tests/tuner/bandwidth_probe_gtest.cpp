// `contactlab probe` and its machine file (tuner/bandwidth_probe.hpp): options checked before
// anything runs, every point measured and positive, the document's schema read back strictly
// (a round trip; unknown fields, wrong kinds and bad curves refused with the path), and the
// command end to end: a table, a file, and one-line errors that leave an earlier file alone.
#include <gtest/gtest.h>

#include <fstream>
#include <functional>
#include <string>

#include "../common/program_test_support.hpp"
#include "contactlab/kernels/error.hpp"
#include "contactlab/tuner/bandwidth_probe.hpp"

namespace contactlab::tuner {
namespace {

using test::run_command;

ProbeOptions small_options() {
  ProbeOptions options;
  options.threads = {1, 2};
  options.working_sets = {96u << 10, 384u << 10};
  options.repetitions = 2;
  return options;
}

TEST(BandwidthProbe, OptionsAreCheckedFirst) {
  ProbeOptions options = small_options();
  EXPECT_NO_THROW(validate(options));
  options.threads = {};
  EXPECT_THROW(validate(options), InputError);
  options.threads = {2, 1};
  EXPECT_THROW(validate(options), InputError);
  options.threads = {0};
  EXPECT_THROW(validate(options), InputError);
  options = small_options();
  options.working_sets = {1024};
  EXPECT_THROW(validate(options), InputError);
  options.working_sets = {1u << 20, 1u << 20};
  EXPECT_THROW(validate(options), InputError);
  options = small_options();
  options.repetitions = 0;
  EXPECT_THROW(validate(options), InputError);
}

TEST(BandwidthProbe, EveryPointMeasuredAndTheFileReadsBack) {
  const ProbeOptions options = small_options();
  const MachineProbe probe = probe_bandwidth(options);
  ASSERT_EQ(probe.working_sets.size(), 2u);
  for (const ProbedWorkingSet& set : probe.working_sets) {
    ASSERT_EQ(set.bytes_per_s.size(), 2u);
    EXPECT_EQ(set.bytes_per_s[0].first, 1);
    EXPECT_EQ(set.bytes_per_s[1].first, 2);
    for (const auto& point : set.bytes_per_s) EXPECT_GT(point.second, 1e6);
    EXPECT_EQ(set.bytes % 24, 0u) << "three arrays of whole doubles";
  }
  const nlohmann::json doc = probe_document(probe, options, collect_context("test", 2));
  EXPECT_EQ(doc["kind"], "contactlab-machine-probe");
  EXPECT_EQ(doc["label"], "measured");
  const std::string path = test::temp_dir("probe") + "/machine.json";
  std::ofstream(path) << doc.dump(1);
  const MachineProbe back = read_machine_file(path);
  ASSERT_EQ(back.working_sets.size(), 2u);
  EXPECT_EQ(back.working_sets[1].bytes, probe.working_sets[1].bytes);
  EXPECT_EQ(back.working_sets[1].bytes_per_s, probe.working_sets[1].bytes_per_s);
  EXPECT_DOUBLE_EQ(curve_of(back.working_sets[0], 0.0).at(2),
                   probe.working_sets[0].bytes_per_s[1].second);
  // The arithmetic at every thread count, read back as written.
  ASSERT_EQ(probe.operations_per_s.size(), 2u);
  EXPECT_EQ(probe.operations_per_s[0].first, 1);
  EXPECT_EQ(probe.operations_per_s[1].first, 2);
  for (const auto& point : probe.operations_per_s) EXPECT_GT(point.second, 1e6);
  EXPECT_EQ(back.operations_per_s, probe.operations_per_s);
  // A machine file from before the arithmetic probe reads, with none.
  nlohmann::json older = doc;
  older.erase("arithmetic");
  std::ofstream(path, std::ios::trunc) << older.dump(1);
  EXPECT_TRUE(read_machine_file(path).operations_per_s.empty());
  EXPECT_THROW(probe_arithmetic(0, 1), InputError);
  EXPECT_THROW(probe_arithmetic(1, 0), InputError);
}

// A machine file with `edit` applied to a valid one: the error names the file and the path.
std::string error_of(const std::function<void(nlohmann::json&)>& edit) {
  ProbeOptions options = small_options();
  MachineProbe probe;
  probe.working_sets = {{96u << 10, {{1, 2e9}, {2, 3e9}}}, {1u << 20, {{1, 1e9}, {2, 1.5e9}}}};
  probe.operations_per_s = {{1, 4e10}, {2, 8e10}};
  nlohmann::json doc = probe_document(probe, options, collect_context("test", 2));
  edit(doc);
  const std::string path = test::temp_dir("probe_bad") + "/machine.json";
  std::ofstream(path) << doc.dump(1);
  try {
    read_machine_file(path);
  } catch (const InputError& e) {
    return e.what();
  }
  return "accepted";
}

TEST(BandwidthProbe, ABadMachineFileIsOneErrorNamingWhere) {
  EXPECT_EQ(error_of([](nlohmann::json&) {}), "accepted");
  EXPECT_NE(error_of([](nlohmann::json& d) { d["extra"] = 1; }).find("unknown field 'extra'"),
            std::string::npos);
  EXPECT_NE(error_of([](nlohmann::json& d) { d["kind"] = "contactlab-sweep"; }).find("$.kind"),
            std::string::npos);
  EXPECT_NE(error_of([](nlohmann::json& d) {
              d["working_sets"][0]["points"][1]["threads"] = 1;
            }).find("$.working_sets[0].points"),
            std::string::npos);
  EXPECT_NE(
      error_of([](nlohmann::json& d) { d["working_sets"][1]["bytes"] = 1024; }).find("ascending"),
      std::string::npos);
  EXPECT_NE(error_of([](nlohmann::json& d) {
              d["working_sets"][0].erase("points");
            }).find("missing field 'points'"),
            std::string::npos);
  EXPECT_NE(error_of([](nlohmann::json& d) {
              d["arithmetic"][1]["threads"] = 1;
            }).find("$.arithmetic[1]: thread counts must be ascending"),
            std::string::npos);
  EXPECT_NE(error_of([](nlohmann::json& d) {
              d["arithmetic"][0]["operations_per_s"] = 0;
            }).find("$.arithmetic[0]: threads must be >= 1"),
            std::string::npos);
  EXPECT_NE(error_of([](nlohmann::json& d) { d["arithmetic"] = 3; }).find("$.arithmetic"),
            std::string::npos);
  EXPECT_THROW(read_machine_file("/nonexistent/machine.json"), InputError);
}

TEST(ProbeCli, PrintsTheTableAndWritesTheMachineFile) {
  const std::string dir = test::temp_dir("probe_cli");
  const auto r = run_command(test::contactlab_exe() + " probe --threads 1,2 --sizes 96K,384K " +
                             "--repetitions 2 --json " + dir + "/out/machine.json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("GB/s"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("of P x 1 thread"), std::string::npos) << r.output;
  const MachineProbe back = read_machine_file(dir + "/out/machine.json");
  EXPECT_EQ(back.working_sets.size(), 2u);
}

TEST(ProbeCli, BadOptionsAreOneLineAndLeaveAnEarlierFile) {
  const std::string dir = test::temp_dir("probe_cli_bad");
  const std::string file = dir + "/machine.json";
  std::ofstream(file) << "earlier\n";
  for (const std::string& args :
       {std::string("--sizes 0"), std::string("--sizes 12Q"), std::string("--threads 2,1"),
        std::string("--threads x"), std::string("--repetitions 0"), std::string("--sizes 1K")}) {
    const auto r = run_command(test::contactlab_exe() + " probe " + args + " --json " + file);
    EXPECT_EQ(r.exit_code, 2) << args << ": " << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << args << ": " << r.output;
    EXPECT_EQ(test::slurp(file), "earlier\n") << args;
  }
}

}  // namespace
}  // namespace contactlab::tuner
