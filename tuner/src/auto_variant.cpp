// Calibration and `--variant auto` policies on top of tune() and the tuning cache.
#include "contactlab/tuner/auto_variant.hpp"

#include <fmt/core.h>

#include "contactlab/tuner/progress.hpp"
#include "methods/methods.hpp"

namespace contactlab::tuner {

void print_progress(const std::string& line) { fmt::print(stderr, "contactlab: {}\n", line); }

Calibration machine_calibration(TuningCache& cache, const TuneOptions& options, int threads,
                                bool recalibrate, const ProgressFn& progress) {
  const auto cached = cache.calibration();
  // A cached fit serves when it priced every structure asked for (e.g. not the grid=hashed ones
  // of `tune --grids dense,hashed` after a default calibration).
  bool covered = cached.has_value();
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
    calibration = calibrate_machine(options, threads, bar.meter());
    bar.finish(calibration.seconds);
  } else {
    calibration = calibrate_machine(options, threads);
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
