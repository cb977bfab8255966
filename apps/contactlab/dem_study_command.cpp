// `contactlab dem variants`: the force variants' speed against error, on a config's scene or a
// checkpoint of it.
#include <fmt/core.h>

#include <memory>
#include <string>
#include <vector>

#include "cli_shared.hpp"
#include "contactlab/dem/config.hpp"
#include "contactlab/kernels/atomic_file.hpp"
#include "contactlab/kernels/error.hpp"
#include "contactlab/tuner_dem/variant_study.hpp"
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

}  // namespace

std::vector<Subcommand> add_dem_study_commands(CLI::App& dem_app, const std::string& command_line) {
  auto variants = std::make_shared<DemVariantsCommand>();
  CLI::App* variants_app = dem_app.add_subcommand(
      "variants", "force variants against the default: speed and position difference");
  variants->start_.add_options(variants_app, "thread counts (default 1,2)",
                               "timed steps per variant (200)");
  variants_app->add_option("--variant", variants->variants_, "only these (repeatable)");
  variants_app->add_option("--chunks", variants->chunks_, "chunk sizes to enumerate (1,16)")
      ->delimiter(',');
  return {{variants_app, [=] { return variants->run(); }},
          add_dem_profile_command(dem_app, command_line),
          add_dem_partition_command(dem_app, command_line),
          add_dem_tile_command(dem_app)};
}

}  // namespace contactlab::cli
