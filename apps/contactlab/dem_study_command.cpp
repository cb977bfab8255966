// `contactlab dem variants` and `dem profile`: the force variants' speed against error, and
// the report's profile (phase split, serial fraction, Amdahl bound against the measured
// speed-up), on a config's scene or a checkpoint of it.
#include <fmt/core.h>
#include <omp.h>

#include <algorithm>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "cli_shared.hpp"
#include "contactlab/dem/checkpoint.hpp"
#include "contactlab/dem/config.hpp"
#include "contactlab/dem/variant_study.hpp"
#include "contactlab/kernels/atomic_file.hpp"
#include "contactlab/kernels/error.hpp"
#include "dem_start.hpp"

namespace contactlab::cli {
namespace {

namespace dem = contactlab::dem;

// Every force variant (or the listed ones) against the deterministic default on a config's
// scene: speed, speed-up and the largest position difference after the same steps.
struct DemVariantsCommand {
  DemStart start_;
  std::vector<std::string> variants_;
  std::vector<int> chunks_{1, 16};
  int run() const {
    const dem::DemConfig config = start_.checked_config();
    std::vector<dem::ForceVariant> variants;
    for (const std::string& v : variants_) variants.push_back(dem::parse_force_variant(v));
    if (variants.empty()) variants = dem::force_variants(chunks_);
    const dem::Particles particles = dem::make_particles(config);
    auto make_engine = [&](const dem::ForceVariant& variant, int threads) {
      return start_.engine(config, particles, variant, threads);
    };
    fmt::print("dem variants '{}': {} particles, {} steps each after one untimed step\n",
               config.name, particles.size(), start_.steps);
    fmt::print("{:<52} {:>7} {:>16} {:>8} {:>14}  {}\n", "variant", "threads", "particle-steps/s",
               "speedup", "max |dx| / d", "same as default");
    for (const dem::VariantStudyRow& r :
         dem::variant_study(make_engine, variants, start_.threads, start_.steps)) {
      fmt::print("{:<52} {:>7} {:>16.4g} {:>8.3f} {:>14.3g}  {}\n", dem::to_string(r.variant),
                 r.threads, r.particle_steps_per_s, r.speedup, r.max_deviation,
                 r.bit_identical ? "bit-identical" : "differs");
    }
    fmt::print(
        "\nspeedup: over ordered/static (the default) at the same thread count; max |dx| / d: "
        "the largest position difference from the default's run, in particle diameters\n");
    return 0;
  }
};

// The report's profile: the phase split at one thread, the serial fraction, the Amdahl bound
// it implies and the measured speed-up beside it.
struct DemProfileCommand {
  DemStart start_;
  std::string variant_ = "ordered/static";
  int run() const {
    const dem::DemConfig config = start_.checked_config();
    const dem::ForceVariant variant = dem::parse_force_variant(variant_);
    if (start_.threads.front() != 1) {
      throw InputError("--threads must start with 1 (the speed-ups are over one thread)");
    }
    const std::uint64_t steps = start_.steps;
    const dem::Particles particles = dem::make_particles(config);
    struct Measured {
      int threads;
      double seconds;
      dem::PhaseTimes phases;
    };
    std::vector<Measured> runs;
    for (const int threads : start_.threads) {
      const std::unique_ptr<dem::Engine> started =
          start_.engine(config, particles, variant, threads);
      dem::Engine& engine = *started;
      engine.step();  // untimed: first touches
      const dem::PhaseTimes before = engine.phase_times();
      const double t0 = omp_get_wtime();
      engine.run_steps(steps);
      const double seconds = omp_get_wtime() - t0;
      runs.push_back({threads, seconds, engine.phase_times() - before});
    }
    const Measured& one = runs.front();
    const double total = one.phases.total_s();
    fmt::print("dem profile '{}': {} particles, variant {}, {} steps per thread count\n\n",
               config.name, particles.size(), dem::to_string(variant), steps);
    fmt::print("phase split at 1 thread (the report: forces 80 %, update 15 %, candidates 5 %)\n");
    const std::pair<const char*, double> phases[] = {
        {"candidates (neighbour list)", one.phases.neighbor_s},
        {!variant.fused_update || variant.accumulation != dem::Accumulation::kOrdered
             ? "pair forces"
             : "pair forces + reduction + update (fused)",
         one.phases.pair_forces_s},
        {"reduction", one.phases.reduction_s},
        {"wall forces (serial)", one.phases.walls_s},
        {variant.serial_walls ? "update" : "update (incl. wall forces)", one.phases.update_s},
        {"integration", one.phases.integrate_s}};
    for (const auto& [name, seconds] : phases) {
      fmt::print("  {:<42} {:>9.4f} s {:>6.1f} %\n", name, seconds, 100.0 * seconds / total);
    }
    // Serial, as an upper bound: the neighbour-list rebuild counted whole (its candidate search
    // runs on every thread; the springs' carrying and the reorder on one) and the serial walls.
    const double serial = (one.phases.neighbor_s + one.phases.walls_s) / total;
    auto amdahl = [](double f, double p) { return 1.0 / (f + (1.0 - f) / p); };
    fmt::print(
        "\nserial fraction (neighbour list, counted whole: an upper bound, + serial walls, at 1 "
        "thread): {:.4f}\n",
        serial);
    fmt::print("{:>7} {:>12} {:>16} {:>9} {:>13} {:>12}\n", "threads", "s/step", "particle-steps/s",
               "speedup", "Amdahl bound", "Karp-Flatt e");
    for (const Measured& m : runs) {
      const double speedup = one.seconds / m.seconds;
      const double p = m.threads;
      const std::string karp_flatt =
          m.threads > 1 ? fmt::format("{:.4f}", (1.0 / speedup - 1.0 / p) / (1.0 - 1.0 / p))
                        : std::string("-");
      fmt::print("{:>7} {:>12.4g} {:>16.4g} {:>9.3f} {:>13.3f} {:>12}\n", m.threads,
                 m.seconds / static_cast<double>(steps),
                 static_cast<double>(particles.size() * steps) / m.seconds, speedup,
                 amdahl(serial, p), karp_flatt);
    }
    fmt::print("Amdahl bound at 2 / 8 / 16 threads: {:.2f} / {:.2f} / {:.2f}\n", amdahl(serial, 2),
               amdahl(serial, 8), amdahl(serial, 16));
    fmt::print(
        "(Karp-Flatt e: the serial fraction the measured speed-up implies, (1/S - 1/p)/(1 - "
        "1/p); above the structural one when the parallel part itself scales worse than p, "
        "e.g. memory bandwidth, load imbalance or a busy core)\n");
    return 0;
  }
};

}  // namespace

std::vector<Subcommand> add_dem_study_commands(CLI::App& dem_app) {
  auto variants = std::make_shared<DemVariantsCommand>();
  CLI::App* variants_app = dem_app.add_subcommand(
      "variants", "force variants against the default: speed and position difference");
  variants->start_.add_options(variants_app, "thread counts (default 1,2)",
                               "timed steps per variant (200)");
  variants_app->add_option("--variant", variants->variants_, "only these (repeatable)");
  variants_app->add_option("--chunks", variants->chunks_, "chunk sizes to enumerate (1,16)")
      ->delimiter(',');
  auto profile = std::make_shared<DemProfileCommand>();
  CLI::App* profile_app = dem_app.add_subcommand(
      "profile", "phase split, serial fraction, Amdahl bound against the measured speed-up");
  profile->start_.add_options(profile_app, "thread counts, from 1 (default 1,2)",
                              "timed steps per thread count (200)");
  profile_app->add_option("--variant", profile->variant_, "force variant (default ordered/static)");
  return {{variants_app, [=] { return variants->run(); }},
          {profile_app, [=] { return profile->run(); }}};
}

}  // namespace contactlab::cli
