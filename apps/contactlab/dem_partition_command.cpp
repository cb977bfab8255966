// `contactlab dem partition CONFIG --ranks R`: the decomposition `dem run --mpi` would use on R
// processes, computed in one process: each rank's slab, particles, ghosts and work, and the
// imbalance.
#include <fmt/core.h>

#include <cmath>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "cli_shared.hpp"
#include "contactlab/dem/checkpoint.hpp"
#include "contactlab/dem/config.hpp"
#include "contactlab/dem/slabs.hpp"
#include "contactlab/kernels/atomic_file.hpp"
#include "contactlab/kernels/error.hpp"
#include "contactlab/tuner/context.hpp"

namespace contactlab::cli {
namespace {

namespace dem = contactlab::dem;
namespace tn = contactlab::tuner;

struct DemPartitionCommand {
  DemStateOptions state_;
  int ranks_ = 0;
  int threads_ = 0;
  std::string json_out_;
  std::string command_line_;

  int run() const {
    if (ranks_ < 1) throw InputError("--ranks must be >= 1");
    const int axis = state_.axis.empty() ? -1 : dem::parse_axis(state_.axis);
    if (!json_out_.empty()) prepare_output_file(json_out_);
    const dem::DemConfig config = dem::read_dem_config(state_.config);
    dem::EngineSettings settings = config.settings;
    settings.threads = resolve_threads(threads_);
    // The particles where the run stands: the config's start, or a checkpoint's (a filled
    // hopper decomposes otherwise than its lattice).
    dem::Particles particles = dem::make_particles(config);
    if (!state_.restart.empty()) {
      particles.set_wall_count(settings.walls.size());
      particles = dem::read_checkpoint_parts(state_.restart, particles).particles;
    }
    const dem::SlabPlan plan = dem::plan_slabs(particles, settings, ranks_, axis);
    const dem::Slabs& slabs = plan.slabs;
    const dem::SlabLoad& load = plan.load;
    fmt::print(
        "dem partition '{}': {} particles over {} ranks, slabs along {}{}; halo {:.4g} m "
        "(2 r_max + skin {:.4g} m); work = 1 per particle + 1 per pair of the start's list "
        "({} pairs)\n",
        config.name, particles.size(), ranks_, dem::axis_name(slabs.axis),
        slabs.periodic ? " (periodic)" : "", plan.halo, plan.skin, plan.pairs);
    double total_work = 0.0;
    std::uint64_t total_ghosts = 0;
    for (int r = 0; r < ranks_; ++r) {
      total_work += load.work[r];
      total_ghosts += load.ghosts[r];
    }
    const double mean = total_work / ranks_;
    fmt::print("{:>5}  {:>27}  {:>10}  {:>8}  {:>12}  {:>9}\n", "rank", "slab [m]", "particles",
               "ghosts", "work", "work/mean");
    nlohmann::json rows = nlohmann::json::array();
    auto bound = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); };
    for (int r = 0; r < ranks_; ++r) {
      const double lo = slabs.cuts[r], hi = slabs.cuts[r + 1];
      fmt::print("{:>5}  {:>27}  {:>10}  {:>8}  {:>12.6g}  {:>9.3f}\n", r,
                 fmt::format("[{:.6g}, {:.6g})", lo, hi), load.particles[r], load.ghosts[r],
                 load.work[r], mean > 0 ? load.work[r] / mean : 0.0);
      rows.push_back({{"rank", r},
                      {"slab_lo_m", bound(lo)},
                      {"slab_hi_m", bound(hi)},
                      {"particles", load.particles[r]},
                      {"ghosts", load.ghosts[r]},
                      {"work", load.work[r]}});
    }
    fmt::print("imbalance (largest work / mean): {:.3f}; ghosts: {:.1f} % of the particles\n",
               load.imbalance,
               100.0 * static_cast<double>(total_ghosts) / static_cast<double>(particles.size()));
    if (!json_out_.empty()) {
      const nlohmann::json doc{
          {"schema_version", 1},
          {"kind", "contactlab-dem-partition"},
          {"context", tn::collect_context(command_line_, settings.threads)},
          {"config", config.name},
          {"restart", state_.restart},
          {"particles", particles.size()},
          {"ranks", ranks_},
          {"axis", dem::axis_name(slabs.axis)},
          {"periodic", slabs.periodic},
          {"halo_m", plan.halo},
          {"skin_m", plan.skin},
          {"pairs", plan.pairs},
          {"imbalance", load.imbalance},
          {"per_rank", rows},
          {"method",
           "Computed, not measured: the neighbour list of the config's start (or of --restart's "
           "particles) in one process; "
           "each particle weighs 1 + half its pairs; slabs along the axis cut where the running "
           "work crosses r W / R (halfway between two particles); ghosts are the particles "
           "within the halo width of another rank's slab (across the periodic boundary too). "
           "The same plan dem run --mpi starts from."}};
      write_json(json_out_, doc);
    }
    return 0;
  }
};

}  // namespace

Subcommand add_dem_partition_command(CLI::App& dem_app, const std::string& command_line) {
  auto partition = std::make_shared<DemPartitionCommand>();
  partition->command_line_ = command_line;
  CLI::App* app = dem_app.add_subcommand(
      "partition", "the slabs, particles, ghosts and work per rank of dem run --mpi on R ranks");
  partition->state_.add_to(*app);
  app->add_option("--ranks", partition->ranks_, "processes")->required();
  app->add_option("--threads", partition->threads_, "threads of the neighbour list");
  app->add_option("--json", partition->json_out_, "write the partition as JSON");
  return {app, [partition] { return partition->run(); }};
}

}  // namespace contactlab::cli
