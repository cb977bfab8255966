// Where the DEM study commands (dem variants, dem profile, tune --dem) start: a config's
// scene, optionally restored from a checkpoint; the thread counts and the timed steps.
#pragma once

#include <CLI/CLI.hpp>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "contactlab/dem/checkpoint.hpp"
#include "contactlab/dem/config.hpp"
#include "contactlab/dem/engine.hpp"
#include "contactlab/kernels/error.hpp"

namespace contactlab::cli {

namespace dem = contactlab::dem;

struct DemStart {
  std::string config;
  std::string restart;
  std::vector<int> threads{1, 2};
  std::uint64_t steps = 200;

  void add_options(CLI::App* app, const char* threads_help, const char* steps_help) {
    app->add_option("config", config, "DEM config")->required();
    app->add_option("--restart", restart, "start from this checkpoint of the config");
    app->add_option("--threads", threads, threads_help)->delimiter(',');
    app->add_option("--steps", steps, steps_help);
  }
  dem::DemConfig checked_config() const {
    if (steps == 0) throw InputError("--steps must be >= 1");
    if (threads.empty()) throw InputError("--threads: give at least one thread count");
    for (const int t : threads) {
      if (t < 1) throw InputError("--threads: every thread count must be >= 1");
    }
    return dem::read_dem_config(config);
  }
  std::unique_ptr<dem::Engine> engine(const dem::DemConfig& scene, const dem::Particles& particles,
                                      const dem::ForceVariant& variant, int thread_count) const {
    dem::EngineSettings settings = scene.settings;
    settings.threads = thread_count;
    settings.force_variant = variant;
    settings.warn_large_overlaps = false;
    auto started = std::make_unique<dem::Engine>(settings, particles);
    if (!restart.empty()) dem::read_checkpoint(*started, restart);
    return started;
  }
};

}  // namespace contactlab::cli
