// The tuner's policies for programs: the machine's calibration (cached, else measured once and
// cached) and `--variant auto` (the cached choice, else tune now and cache the choice).
#pragma once

#include <functional>
#include <string>

#include "contactlab/kernels/scene.hpp"
#include "contactlab/kernels/variant.hpp"
#include "contactlab/tuner/result_schema.hpp"
#include "contactlab/tuner/tune.hpp"

namespace contactlab::tuner {

// Receives one progress line (no trailing newline). Slow steps announce themselves so that a
// user waiting minutes for a first `--variant auto` knows why.
using ProgressFn = std::function<void(const std::string& line)>;

// Prints "contactlab: <line>" to stderr, as the contactlab program always has.
void print_progress(const std::string& line);

// The cache's calibration for this machine and build, or (on a miss, or with `recalibrate`)
// a new one from calibrate_machine, stored in the cache.
Calibration machine_calibration(TuningCache& cache, const TuneOptions& options, int threads,
                                bool recalibrate, const ProgressFn& progress = print_progress);

// `--variant auto`: the tuning cache's choice for this machine, build, scene and thread count;
// on a miss the tuner's search chooses, and the choice is cached. `cache_file` empty = the
// default cache.
Variant auto_variant(const Scene& scene, const SceneRecord& record, double diameter, int threads,
                     const std::string& cache_file, const std::string& command_line,
                     const ProgressFn& progress = print_progress);

}  // namespace contactlab::tuner
