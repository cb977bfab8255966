// What the contactlab subcommands share: their registration interface, the scene options
// (made from the library's one table of scene parameters) and printing helpers.
#pragma once

#include <CLI/CLI.hpp>
#include <cstdint>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "contactlab/kernels/scene.hpp"
#include "contactlab/kernels/scene_generate.hpp"
#include "contactlab/tuner/bandwidth_probe.hpp"
#include "contactlab/tuner/counter_record.hpp"
#include "contactlab/tuner/result_schema.hpp"

namespace contactlab::cli {

// A registered subcommand: its CLI11 app (true once parsed) and what running it does. main
// runs it after parsing, so every parse error is reported before any work starts.
struct Subcommand {
  CLI::App* app = nullptr;
  std::function<int()> run;
};

// The --mpi, --block and --halo options detect and tune share (the MPI modes, detect_mpi.hpp).
struct MpiCliOptions {
  std::string mode;  // replicated or decomposed; empty: no MPI (whether or not under mpirun)
  std::uint32_t block = 200;
  double halo = 0.0;
  // `mode_help` says what --mpi does in this command.
  void add_to(CLI::App& app, const std::string& mode_help) {
    app.add_option("--mpi", mode, mode_help);
    app.add_option("--block", block, "--mpi replicated: block size of the block-cyclic deal");
    app.add_option("--halo", halo,
                   "--mpi decomposed: halo width (default D, or the largest diameter)");
  }
};

// One per file, registered by main in this order (the order of `contactlab --help`).
Subcommand add_scene_command(CLI::App& app);
Subcommand add_detect_command(CLI::App& app, const std::string& command_line);
Subcommand add_variants_command(CLI::App& app);
Subcommand add_sweep_command(CLI::App& app, const std::string& command_line);
Subcommand add_tune_command(CLI::App& app, const std::string& command_line);
Subcommand add_partition_command(CLI::App& app);
Subcommand add_emulate_command(CLI::App& app, const std::string& command_line);
Subcommand add_demo_command(CLI::App& app);
Subcommand add_probe_command(CLI::App& app, const std::string& command_line);
Subcommand add_dem_command(CLI::App& app, const std::string& command_line);
// `dem variants`, `dem profile` and `dem partition`, under the dem command (dem_study_command.cpp).
std::vector<Subcommand> add_dem_study_commands(CLI::App& dem_app, const std::string& command_line);
// `emulate dem-mpi`, under the emulate command (emulate_dem_mpi_command.cpp): sets `run`.
void add_emulate_dem_mpi_command(CLI::App& emulate_app, const std::string& command_line,
                                 std::function<int()>& run);
// `dem partition`, under the dem command (dem_partition_command.cpp).
Subcommand add_dem_partition_command(CLI::App& dem_app, const std::string& command_line);
// `dem tile`, under the dem command (dem_tile_command.cpp).
Subcommand add_dem_tile_command(CLI::App& dem_app);
// `dem profile`, under the dem command (dem_profile_command.cpp).
Subcommand add_dem_profile_command(CLI::App& dem_app, const std::string& command_line);

// `tune --dem CONFIG`: every force variant timed on the config's scene at `threads`, the
// fastest chosen, the default's and the report's regret printed (dem_study_command.cpp).
struct DemTuneRequest {
  std::string config;
  std::string restart;
  std::uint64_t steps = 200;
  int threads = 1;
  std::string json_out;
  bool predict_only = false;  // the calibrated model alone: no candidate timed
  bool exhaustive = false;    // also time every candidate (ground truth)
  int verify_rounds = 3;      // interleaved rounds over the choices, default and report's
};
int tune_dem(const DemTuneRequest& request);

// Where the particles come from: a file, or a generator spec.
struct SceneOptions {
  std::string input_;
  std::string kind_ = "clustered";
  double diameter_ = 0.0;  // 0 until given: file scenes may carry their own diameters
  bool diameter_given_ = false;
  std::string box_;
  SceneSpec spec_;  // its numbers are bound to the options of kSceneParameters

  // `with_input`: --input and the kind as --scene (detect, tune); else the kind is --kind.
  void add_to(CLI::App& app, bool with_input);
  SceneSpec spec() const;
  void require_diameter() const;  // throws InputError
  // The scene and its description for result files.
  std::pair<Scene, tuner::SceneRecord> load() const;
};

// "a,b,c" -> {"a", "b", "c"}; throws InputError on an empty item.
// The run a decomposition is planned on (`dem partition`, `emulate dem-mpi`): the config, where
// the run stands (a checkpoint of it; empty: the config's start) and the slabs' axis (empty: the
// longest).
struct DemStateOptions {
  std::string config;
  std::string restart;
  std::string axis;

  void add_to(CLI::App& app);
};

// The stated network of the MPI emulations (`emulate mpi`, `emulate dem-mpi`): latency per
// message, bandwidth per link and where the figures come from (each command states its own
// default source).
struct NetworkOptions {
  double latency_s = 1.5e-6;
  double bandwidth = 5.0e9;  // bytes/s
  std::string source;

  void add_to(CLI::App& app);
  void check() const;  // InputError for latency < 0 or bandwidth <= 0
};

// The memory system an emulation prices bytes against (`dem profile --emulate`, `emulate
// threads`): a machine file from `contactlab probe` and the ceiling beyond its cores, stated
// with its source (docs/emulation.md, "Bandwidth").
struct MemoryOptions {
  std::string machine_file;
  double ceiling_gb_s = 0.0;
  std::string ceiling_source;

  // `prices`: what the bytes price, for --machine's help.
  void add_to(CLI::App& app, const std::string& prices);
  // Nothing without --machine; else the file read back strictly. InputError for a ceiling
  // without a machine file, one <= 0, or one without its source.
  std::optional<tuner::MemorySystem> load() const;
};

std::vector<std::string> split_list(const std::string& text);
// "1,2,4" -> {1, 2, 4}; throws InputError naming `option` on an item that is not a whole
// number >= 1.
std::vector<int> int_list(const std::string& text, const char* option);

void print_counters(const tuner::CounterRecord& counters);

// A command's --json document, indented, written atomically (the old file kept on a failure),
// then "wrote PATH".
void write_json(const std::string& path, const nlohmann::json& doc);

}  // namespace contactlab::cli
