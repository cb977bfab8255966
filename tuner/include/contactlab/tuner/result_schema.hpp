// The result file every measuring command writes and every reader checks (docs/result-schema.md):
//   { "schema_version": 1, "context": {...}, "runs": [ {status, parameters, samples,
//     aggregates, work, phases, work_counts, counters[]}, ... ] }
// Writers go through write_result_file (atomic); readers through parse_result /
// read_result_file, which reject unknown or missing fields with the JSON path.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "contactlab/kernels/scene.hpp"
#include "contactlab/kernels/scene_generate.hpp"
#include "contactlab/support/json_reader.hpp"
#include "contactlab/support/statistics.hpp"
#include "contactlab/tuner/context.hpp"
#include "contactlab/tuner/counter_record.hpp"

namespace contactlab::tuner {

inline constexpr int kSchemaVersion = 1;

// ok: measured; invalid: measured but the result is wrong (contacts differ between
// repetitions or from the expected count); failed: no measurement (message says why).
enum class RunStatus { kOk, kInvalid, kFailed };
std::string_view to_string(RunStatus status);
RunStatus parse_run_status(std::string_view text);  // throws InputError

// Where the particles came from: a generator and its parameters, or a file.
struct SceneRecord {
  std::string kind;                 // uniform, clustered, blobs, polydisperse, core, file
  std::optional<std::string> path;  // file scenes
  std::uint64_t n = 0;
  std::optional<double> diameter;     // null when the particles carry their own diameters
  std::optional<std::uint64_t> seed;  // generated scenes
  std::optional<double> core, background, blob_radius, size_ratio;
  std::optional<int> blob_count;
  std::array<double, 6> box{};  // xmin, ymin, zmin, xmax, ymax, zmax
  std::string checksum;         // scene_checksum as 16 hex digits
};
SceneRecord describe_generated_scene(const SceneSpec& spec, const Scene& scene);
SceneRecord describe_file_scene(const std::string& path, const Scene& scene, double diameter);

struct RunParameters {
  std::string variant;  // canonical loop/order/stencil/schedule
  int threads = 0;      // threads used
  SceneRecord scene;
  RepetitionPolicy repetition;
};

// Raw values, one entry per timed repetition (warm-up runs are not kept).
struct RunSamples {
  std::vector<double> setup_s;                     // T_s
  std::vector<double> detect_s;                    // T_c
  std::vector<double> total_s;                     // T_s + T_c
  std::vector<std::vector<double>> thread_busy_s;  // [repetition][thread], detection loop
  std::vector<double> imbalance;                   // (t_max - t_mean) / t_max per repetition
  // The sweep round each repetition belongs to (experiments with "rounds"; absent otherwise):
  // ratios between two runs are taken within a round.
  std::optional<std::vector<int>> round;
  // Parts of the phases by name, one entry per repetition: "registration" and "reorder" of T_s,
  // "assembly" of T_c (after the slowest thread's loop). Each is summarised in the run's
  // `phases` under its name. Absent in files written before them.
  std::map<std::string, std::vector<double>> parts_s;
};

struct RunAggregates {
  Summary setup_s, detect_s, total_s, imbalance;
  std::vector<double> thread_busy_median_s;  // per thread, over repetitions
  int repetitions = 0;
  int warmup_runs = 0;
  StopReason stop_reason = StopReason::kFixedCount;
  double measurement_s = 0.0;  // wall time of the whole measurement, warm-up included
};

struct RunWork {
  std::uint64_t candidate_tests = 0;
  std::uint64_t contact_pairs = 0;
  std::uint32_t max_cell_occupancy = 0;
  std::array<int, 3> grid{};
};

// The run's contacts against an exact reference variant: pairs it missed and pairs it found
// that are not contacts (nonzero only for single precision, or a bug).
struct ContactCheck {
  std::string reference;  // the reference variant
  std::uint64_t missing_pairs = 0;
  std::uint64_t extra_pairs = 0;
};

// One MPI process of a `detect --mpi` run: its phases (seconds) and loads.
struct MpiRankRecord {
  int rank = 0;
  int threads = 0;
  double read_s = 0.0, exchange_s = 0.0, registration_s = 0.0, detection_s = 0.0, output_s = 0.0,
         total_s = 0.0;
  std::uint64_t owned_particles = 0;  // replicated: every particle
  std::uint64_t halo_particles = 0;   // ghosts received (decomposed)
  std::uint64_t halo_sent = 0;        // copies sent as other ranks' ghosts
  std::uint64_t halo_bytes = 0;       // bytes received in the halo exchange
  std::uint64_t migrated_in = 0;      // particles received from other ranks' reads
  std::uint64_t candidate_tests = 0;  // the rank's work
  std::uint64_t contact_pairs = 0;    // contacts it emitted (each contact by one rank)
  std::uint64_t peak_rss_bytes = 0;   // getrusage maximum resident set
};

// How a `detect --mpi` run was spread: the mode, its parameters, every rank, and the maxima
// over ranks (the run's times are the slowest rank's).
struct MpiRecord {
  std::string mode;  // replicated or decomposed
  int ranks = 1;
  std::uint32_t block = 0;  // replicated: block of the block-cyclic deal (0 in decomposed)
  double halo_width = 0.0;  // decomposed: halo width = the partition's cell width (0 replicated)
  double work_imbalance = 0.0;  // max / mean - 1 of candidate_tests over ranks
  std::uint64_t max_peak_rss_bytes = 0;
  std::vector<MpiRankRecord> per_rank;
};

struct RunRecord {
  RunStatus status = RunStatus::kOk;
  std::string message;  // empty when ok
  RunParameters parameters;
  RunSamples samples;
  std::optional<RunAggregates> aggregates;    // null when failed
  std::optional<RunWork> work;                // null when failed
  std::vector<CounterRecord> counters;        // each with its source; empty when none requested
  std::optional<ContactCheck> contact_check;  // null when not checked
  // The kernel's own phases and work, by name, so that another kernel family reports its
  // phases and counts without a schema change: for contact detection "setup" and "detect"
  // (the same summaries as aggregates.setup_s and detect_s) and "candidate_tests",
  // "contact_pairs", "max_cell_occupancy" (as in work). Empty when failed; absent from files
  // written before they existed (read as empty).
  std::map<std::string, Summary> phases;
  std::map<std::string, std::uint64_t> work_counts;
  std::optional<MpiRecord> mpi;  // detect --mpi only (absent otherwise)
};

struct ResultFile {
  int schema_version = kSchemaVersion;
  Context context;
  std::vector<RunRecord> runs;
};

// Writing.
void to_json(nlohmann::json& j, const CounterRecord& v);
void to_json(nlohmann::json& j, const Context& v);
void to_json(nlohmann::json& j, const SceneRecord& v);
void to_json(nlohmann::json& j, const RunRecord& v);
void to_json(nlohmann::json& j, const ResultFile& v);

// Strict reading (JsonIn carries the path for messages).
void read(const JsonIn& in, EventCount& out);
void read(const JsonIn& in, CacheLevel& out);
void read(const JsonIn& in, CacheGeometry& out);
void read(const JsonIn& in, SimulationRecord& out);
void read(const JsonIn& in, CounterRecord& out);
void read(const JsonIn& in, CacheInfo& out);
void read(const JsonIn& in, MachineInfo& out);
void read(const JsonIn& in, BuildRecord& out);
void read(const JsonIn& in, OpenMpInfo& out);
void read(const JsonIn& in, PapiEventProbe& out);
void read(const JsonIn& in, PapiContext& out);
void read(const JsonIn& in, Context& out);
void read(const JsonIn& in, SceneRecord& out);
void read(const JsonIn& in, RunParameters& out);
void read(const JsonIn& in, RunSamples& out);
void read(const JsonIn& in, RunAggregates& out);
void read(const JsonIn& in, RunWork& out);
void read(const JsonIn& in, ContactCheck& out);
void read(const JsonIn& in, MpiRankRecord& out);
void read(const JsonIn& in, MpiRecord& out);
void read(const JsonIn& in, RunRecord& out);
void read(const JsonIn& in, ResultFile& out);

// nlohmann entry points: j.get<ResultFile>() reads strictly from the root ("$").
void from_json(const nlohmann::json& j, ResultFile& out);
void from_json(const nlohmann::json& j, RunRecord& out);

// Throws SchemaError ("$.path: what") for any departure from the schema, including a
// schema_version other than kSchemaVersion.
ResultFile parse_result(const nlohmann::json& j);
// Throws InputError naming the file (unreadable, not JSON, or SchemaError's path).
ResultFile read_result_file(const std::string& path);
// Atomic: an existing file is never left half-written.
void write_result_file(const std::string& path, const ResultFile& result);

}  // namespace contactlab::tuner

namespace contactlab {

// The statistics' records (contactlab::support) as result files hold them, from the tables in
// result_schema.cpp; declared beside their types, where argument-dependent lookup finds them
// (a vector or a map of them is read by json_reader.hpp's templates, nlohmann calls to_json).
void to_json(nlohmann::json& j, const Summary& v);
void read(const JsonIn& in, Summary& out);
void read(const JsonIn& in, MedianInterval& out);
void read(const JsonIn& in, RepetitionPolicy& out);

}  // namespace contactlab
