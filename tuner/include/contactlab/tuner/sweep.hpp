// Sweeps: every point (scene x variant x threads) of an experiment config, measured in a seeded
// interleaved order and appended to a result file after each point, so that an interrupted
// sweep loses nothing and `resume` continues where it stopped.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "contactlab/kernels/contact_list.hpp"
#include "contactlab/kernels/scene.hpp"
#include "contactlab/tuner/experiment.hpp"
#include "contactlab/tuner/result_schema.hpp"

namespace contactlab::tuner {

struct SweepOptions {
  std::string out;           // result file (schema of docs/result-schema.md)
  bool resume = false;       // keep the points already in `out` and run the rest
  bool progress = false;     // progress bar with ETA on stderr
  std::string command_line;  // recorded in the context
};

struct SweepSummary {
  std::size_t points = 0;   // in the experiment
  std::size_t skipped = 0;  // already in the file (resume)
  std::size_t ok = 0, invalid = 0, failed = 0;
  double seconds = 0.0;
};

// Throws InputError for an unusable config or output path before anything is measured; a
// point that fails is recorded with status "failed" and the sweep goes on.
SweepSummary run_sweep(const Experiment& experiment, const SweepOptions& options);

// A scene of an experiment, loaded or generated, with its description for result files.
std::pair<Scene, SceneRecord> load_experiment_scene(const ExperimentScene& scene);

// Pairs in exactly one of two canonical contact lists: (missing from `candidate`, extra in it).
std::pair<std::uint64_t, std::uint64_t> contact_differences(const ContactList& reference,
                                                            const ContactList& candidate);

// Identity of a measured point in a result file: scene checksum, variant, threads.
std::string point_key(const std::string& scene_checksum, const std::string& variant, int threads);

}  // namespace contactlab::tuner
