// Experiment configs: which scenes, variants, thread counts and measurements a sweep runs.
// JSON, schema-versioned, validated strictly (unknown or missing keys are errors naming their
// JSON path). Format and examples: docs/experiments.md.
#pragma once

#include <cstdint>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <vector>

#include "contactlab/kernels/scene_generate.hpp"
#include "contactlab/kernels/variant.hpp"
#include "contactlab/support/statistics.hpp"

namespace contactlab::tuner {

inline constexpr int kExperimentSchemaVersion = 1;

// A scene of the experiment: generated (kind, n, diameter, seed, parameters) or a file.
struct ExperimentScene {
  std::string name;  // label in results and tables
  SceneSpec spec;    // used when file is empty
  std::string file;  // particle file (text or binary)
  double diameter = 0.0;
};

struct Experiment {
  std::string name;
  std::string description;
  std::vector<ExperimentScene> scenes;
  // Variant patterns; "{k}" in a pattern is replaced by every chunk of `chunks`.
  std::vector<std::string> variant_patterns;
  std::vector<int> chunks;
  std::vector<int> threads;
  // "repetitions": {"warmup", "min" (timed runs), "max", "target_ci" (relative half-width of
  // the median's 95% interval; repetition is adaptive when given), "budget_s" (per point),
  // "rounds"}.
  RepetitionPolicy repetitions;
  // Every point is visited once per round, each round in its own seeded order, with the policy's
  // warm-up and fixed count each visit; the samples carry their round, so that two points can
  // be compared by ratios within rounds (a slow spell of the machine then slows both). 1: each
  // point measured once, its repetitions back to back.
  int rounds = 1;
  bool papi = false;
  std::string cache_sim;         // "", "host" or "fx10"
  bool check_contacts = true;    // count wrong contacts against the double-precision reference
  std::uint64_t order_seed = 1;  // seeds the interleaved order of the points

  std::vector<Variant> variants() const;  // the patterns expanded, duplicates removed
};

// One configuration to measure: scene index, variant, threads.
struct ExperimentPoint {
  std::size_t scene = 0;
  Variant variant;
  int threads = 1;
  std::string key() const;  // stable identity used by --resume
};

// Every point of the experiment, in a seeded random order that interleaves scenes, variants
// and thread counts, so that slow drift of the machine spreads over all of them; each round has
// its own order (round 0's is the order of order_seed itself).
std::vector<ExperimentPoint> experiment_points(const Experiment& experiment, int round = 0);

// Throws InputError "<file>: <json path>: <problem>" for any invalid, unknown or missing field.
Experiment parse_experiment(const nlohmann::json& document, const std::string& source);
Experiment read_experiment(const std::string& path);

// Chunk lists: "chunks": [1, 2, 4] or {"from": 1, "to": 65536, "factor": 2}.
std::vector<int> powers_of_two(int from, int to);

}  // namespace contactlab::tuner
