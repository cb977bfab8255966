// Calibration and `--variant auto` policies on top of tune() and the tuning cache.
#include "contactlab/tuner/auto_variant.hpp"

#include <fmt/core.h>
#include <omp.h>

#include <algorithm>

#include "contactlab/tuner/progress.hpp"
#include "methods/methods.hpp"

namespace contactlab::tuner {

void print_progress(const std::string& line) { fmt::print(stderr, "contactlab: {}\n", line); }

Calibration machine_calibration(TuningCache& cache, const TuneOptions& options, int threads,
                                bool recalibrate, const ProgressFn& progress) {
  const auto cached = cache.calibration();
  // The calibration is the machine's, cached for every thread count, so it is timed on no more
  // threads than the machine has cores. Timed oversubscribed (`tune --threads 16 --predict-only`
  // on 2 cores, the documented way to plan for a larger machine) the threads took turns on the
  // cores: the output term's seconds per entry came out 200-2,000x its 1-thread value and the
  // model priced the paper scene's half stencil at 0.23 s for 16 threads, where 16 real cores
  // ran it in 0.045 - 0.073 s, and predicted 16 threads slower than 8 (0.040 against 0.012 s).
  const int timed_threads = std::clamp(threads, 1, std::max(1, omp_get_num_procs()));
  // A cached fit serves when it priced every structure asked for (e.g. not the grid=hashed ones
  // of `tune --grids dense,hashed` after a default calibration), was timed on as many threads as
  // this one would be (a 1-thread fit has no schedule terms for 2), and not oversubscribed (a
  // cache written before the clamp above).
  bool covered = cached.has_value() && cached->threads >= timed_threads &&
                 cached->threads <= std::max(1, omp_get_num_procs());
  for (const Variant& structure : structures_of(options)) {
    covered = covered && cached->structures.count(structure_key(structure)) > 0;
  }
  if (!recalibrate && covered) return *cached;
  Calibration calibration;
  if (progress) {
    progress(fmt::format("calibrating the cost model on this machine (once; cached in {})...",
                         cache.path()));
    // The bar on stderr, as the lines: a redrawn line on a terminal, else a line a quarter.
    ProgressBar bar("calibrating");
    calibration = calibrate_machine(options, timed_threads, bar.meter());
    bar.finish(calibration.seconds);
  } else {
    calibration = calibrate_machine(options, timed_threads);
  }
  if (cached && !recalibrate) {  // keep the structures fitted before and not asked for now
    for (const auto& [key, costs] : cached->structures) calibration.structures.emplace(key, costs);
  }
  cache.store_calibration(calibration);
  return calibration;
}

Variant auto_variant(const Scene& scene, const SceneRecord& record, double diameter, int threads,
                     const std::string& cache_file, const std::string& command_line,
                     const ProgressFn& progress) {
  auto say = [&](const std::string& line) {
    if (progress) progress(line);
  };
  TuningCache cache(cache_file.empty() ? TuningCache::default_path() : cache_file);
  if (auto cached = cache.choice(record, diameter, threads)) {
    say(fmt::format("--variant auto: {} (from {})", to_string(*cached), cache.path()));
    return *cached;
  }
  TuneOptions options;
  options.threads = threads;
  const Calibration calibration = machine_calibration(cache, options, threads, false, progress);
  say("--variant auto: no cached choice, tuning...");
  const TuneReport report = tune(scene, record, diameter, options, calibration, command_line);
  cache.store_choice(record, diameter, threads, report.chosen, 0.0);
  say(fmt::format("--variant auto: {} (stored in {})", to_string(report.chosen), cache.path()));
  return report.chosen;
}

}  // namespace contactlab::tuner
