// The tune report (tune.json, docs/tuning.md) as types: what `contactlab tune --json` writes
// and what readers get back, through field tables with the strict reader's rules (unknown keys
// rejected, missing ones named, errors with their JSON path), like the result files.
#pragma once

#include <array>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "contactlab/support/json_reader.hpp"
#include "contactlab/tuner/result_schema.hpp"

namespace contactlab::tuner {

inline constexpr int kTuneSchemaVersion = 1;

// Timed runs of one choice in the final verification (a summary of the tuned phase).
struct VerifiedTiming {
  double median_s = 0.0;
  double ci95_low_s = 0.0;
  double ci95_high_s = 0.0;
  std::vector<double> samples_s;
};

// A paired ratio minus one with its 95% interval.
struct RatioToExhaustive {
  double ratio_minus_one = 0.0;
  std::array<double, 2> ci95{};
};

// What the verification adds to an entry: its timings and its regret against the fastest
// verified choice (and against the exhaustive best when there is one).
struct Verified {
  std::optional<VerifiedTiming> measured;
  std::optional<double> regret;
  std::optional<std::array<double, 2>> regret_ci95;
  std::optional<RatioToExhaustive> vs_exhaustive;
};

// One tuning method's entry. The common fields first; then each method's own, present only
// for the methods that have them (model: predicted_s, structures; search: screening and the
// chunk search's costs; exhaustive: largest_equivalent_chunk, rounds; both: chunks_measured).
// A chunk of 0 is the schedule's default: with `static`, one block per thread (the sweep's last
// point, the largest chunk).
struct MethodEntry : Verified {
  std::string method;
  std::string variant;
  int chunk = 0;
  int timed_runs = 0;
  double tuning_cost_s = 0.0;
  std::optional<double> predicted_s;
  std::optional<nlohmann::json> structures;
  std::optional<int> chunk_search_timed_runs;
  std::optional<int> evaluations;
  std::optional<double> screening_cost_s;
  std::optional<double> model_cost_s;
  std::optional<double> chunk_search_cost_s;
  std::optional<nlohmann::json> screening;
  std::optional<nlohmann::json> chunks_measured;
  std::optional<int> largest_equivalent_chunk;
  std::optional<int> rounds;
};

// A classic chunk formula priced on the tuned structure (chunk_formulas.hpp).
struct ClassicEntry : Verified {
  std::string name;
  int chunk = 0;
  std::string inputs;
  std::string structure;
  std::optional<std::string> variant;  // with the tuned schedule kind; set when verified
};

struct Prediction {
  int threads = 0;
  std::string variant;
  double predicted_s = 0.0;
  std::string label;  // always says "predicted"
};

struct VerificationSummary {
  int rounds = 0;
  int distinct_variants = 0;
  std::string best;
  std::string regret_against;
};

struct CalibrationSummary {
  std::string source;
  double seconds = 0.0;
};

// `tune --mpi` (docs/mpi.md): the ranks ran the kernel together, each on its own part; every
// time in the document is the slowest rank's.
struct TuneMpi {
  std::string mode;  // replicated or decomposed
  int ranks = 1;
  std::uint32_t block = 0;  // replicated: block of the block-cyclic deal (0 in decomposed)
  double halo_width = 0.0;  // decomposed: the partition's cell width (0 in replicated)
};

struct TuneDocument {
  int schema_version = kTuneSchemaVersion;
  Context context;
  SceneRecord scene;
  std::optional<double> diameter;  // null for scenes with per-particle diameters
  int threads = 0;
  std::vector<int> chunk_grid;
  CalibrationSummary calibration;
  std::vector<MethodEntry> methods;
  std::vector<ClassicEntry> classic;
  std::vector<Prediction> predictions;
  std::optional<VerificationSummary> verification;  // absent with --predict-only
  std::optional<TuneMpi> mpi;                       // tune --mpi only

  const MethodEntry* method(const std::string& name) const;  // nullptr when it did not run
};

nlohmann::json to_json_value(const TuneDocument& document);
// An entry's verification fields alone (as in a method's entry), for rows kept as JSON (the
// model's structures).
nlohmann::json to_json_value(const Verified& verified);
void read(const JsonIn& in, TuneDocument& out);
// Throws InputError naming the file and the JSON path.
TuneDocument read_tune_document(const std::string& path);

}  // namespace contactlab::tuner
