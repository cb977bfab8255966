// `contactlab emulate dem-mpi CONFIG`: dem run --mpi at 1..1024 ranks, strong and weak scaling,
// predicted from the slabs' per-rank work and ghosts, a cost per unit of work measured here in
// one process and a stated network model (tuner_dem/mpi_emulation.hpp); checked against
// scripts/dem-mpi-compare's measurements where given.
#include <fmt/core.h>
#include <omp.h>

#include <cmath>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cli_shared.hpp"
#include "contactlab/dem/checkpoint.hpp"
#include "contactlab/dem/config.hpp"
#include "contactlab/kernels/atomic_file.hpp"
#include "contactlab/kernels/error.hpp"
#include "contactlab/tuner/context.hpp"
#include "contactlab/tuner_dem/mpi_emulation.hpp"

namespace contactlab::cli {
namespace {

namespace dem = contactlab::dem;
namespace tn = contactlab::tuner;

struct EmulateDemMpiCommand {
  DemStateOptions state_;
  std::string ranks_ = "1,2,4,8,16,32,64,128,256,512,1024";
  std::uint64_t steps_ = 100;
  NetworkOptions network_{.source =
                              "an InfiniBand-class network as commonly cited (about 1.5 us MPI "
                              "latency, 5 GB/s per link and direction); not measured here"};
  std::string measured_;
  std::string json_out_;
  std::string command_line_;

  int run() const {
    const std::vector<int> ranks = int_list(ranks_, "--ranks");
    const int axis = state_.axis.empty() ? -1 : dem::parse_axis(state_.axis);
    if (steps_ == 0) throw InputError("--steps must be >= 1");
    network_.check();
    nlohmann::json measured;
    if (!measured_.empty()) {
      std::ifstream in(measured_);
      if (!in) throw InputError("cannot open --measured '" + measured_ + "'");
      measured = nlohmann::json::parse(in, nullptr, false);
      if (measured.is_discarded() || measured.value("kind", "") != "contactlab-dem-mpi-compare") {
        throw InputError(measured_ + ": not a scripts/dem-mpi-compare result file");
      }
    }
    if (!json_out_.empty()) prepare_output_file(json_out_);
    const dem::DemConfig config = dem::read_dem_config(state_.config);
    dem::EngineSettings settings = config.settings;
    settings.threads = 1;
    settings.warn_large_overlaps = false;
    // A decomposed run's ranks run the whole pair list (near_pairs.hpp: not with a halo), so
    // its unit of work is timed on it.
    settings.near_margin = 0.0;
    // The cost of a unit of work here: one process, one thread, from the run's start.
    dem::Engine engine(settings, dem::make_particles(config));
    if (!state_.restart.empty()) dem::read_checkpoint(engine, state_.restart);
    engine.run_steps(10);  // untimed
    const double t0 = omp_get_wtime();
    engine.run_steps(steps_);
    const double step_s = (omp_get_wtime() - t0) / static_cast<double>(steps_);
    const dem::Particles& particles = engine.particles();
    const dem::PairList& pairs = engine.pairs();
    double work = 0.0;
    for (const double w : dem::particle_work(particles, pairs)) work += w;
    const double per_work = step_s / work;
    dem::EngineSettings planning = engine.settings();
    const dem::NetworkModel network{network_.latency_s, network_.bandwidth};
    const auto strong =
        dem::emulate_dem_mpi_strong(particles, pairs, planning, ranks, axis, per_work, network);
    const auto weak =
        dem::emulate_dem_mpi_weak(particles, pairs, planning, ranks, axis, per_work, network);
    fmt::print(
        "emulate dem-mpi '{}' (PREDICTED): {} particles, {} pairs; one process measured {:.4g} "
        "s a step over {} steps ({:.4g} s per unit of work); network {:.3g} s latency, {:.3g} "
        "B/s\n",
        config.name, particles.size(), pairs.size(), step_s, steps_, per_work, network_.latency_s,
        network_.bandwidth);
    fmt::print("{:>6} {:>12} {:>10} {:>12} {:>10} {:>9} {:>8} {:>12} {:>10}\n", "ranks",
               "strong step", "speed-up", "exchange s", "imbalance", "ghosts", "nbrs", "weak step",
               "weak eff.");
    nlohmann::json rows = nlohmann::json::array();
    for (std::size_t k = 0; k < ranks.size(); ++k) {
      const dem::DemMpiPoint& s = strong[k];
      const dem::DemMpiPoint& w = weak[k];
      fmt::print("{:>6} {:>12.4g} {:>10.2f} {:>12.3g} {:>10.3f} {:>9} {:>8} {:>12.4g} {:>10.3f}\n",
                 s.ranks, s.step_s, s.speedup, s.exchange_s, s.imbalance, s.ghosts_max,
                 s.neighbours_max, w.step_s, w.speedup);
      rows.push_back({{"ranks", s.ranks},
                      {"strong",
                       {{"step_s", s.step_s},
                        {"speedup", s.speedup},
                        {"compute_s", s.compute_s},
                        {"exchange_s", s.exchange_s},
                        {"reduction_s", s.reduction_s},
                        {"imbalance", s.imbalance},
                        {"ghosts_max", s.ghosts_max},
                        {"neighbours_max", s.neighbours_max}}},
                      {"weak",
                       {{"step_s", w.step_s},
                        {"efficiency", w.speedup},
                        {"ghosts", w.ghosts_max},
                        {"neighbours", w.neighbours_max}}}});
    }
    // The check against what ran here: the measured speed-up (plain / --mpi) at each rank count
    // the measurement has, against the predicted one.
    nlohmann::json checks = nlohmann::json::array();
    if (!measured.is_null()) {
      for (const auto& point : measured["points"]) {
        const int r = point["ranks"].get<int>();
        const auto at = std::find(ranks.begin(), ranks.end(), r);
        if (at == ranks.end()) continue;
        const double predicted = strong[static_cast<std::size_t>(at - ranks.begin())].speedup;
        const double got = point["speedup_median"].get<double>();
        const double error = predicted / got - 1.0;
        fmt::print("check: {} ranks measured {:.3f}x ({}), predicted {:.3f}x: error {:+.1f} %\n", r,
                   got, measured_, predicted, 100.0 * error);
        checks.push_back({{"ranks", r},
                          {"measured_speedup", got},
                          {"predicted_speedup", predicted},
                          {"relative_error", error}});
      }
    }
    if (!json_out_.empty()) {
      const nlohmann::json doc{
          {"schema_version", 1},
          {"kind", "contactlab-dem-mpi-emulation"},
          {"predicted", true},
          {"context", tn::collect_context(command_line_, 1)},
          {"config", config.name},
          {"restart", state_.restart},
          {"particles", particles.size()},
          {"pairs", pairs.size()},
          {"calibration",
           {{"measured_step_s", step_s}, {"steps", steps_}, {"seconds_per_work", per_work}}},
          {"network",
           {{"latency_s", network_.latency_s},
            {"bandwidth", network_.bandwidth},
            {"source", network_.source}}},
          {"points", rows},
          {"checks", checks},
          {"method",
           "Predicted, not measured. Per rank and step: compute = c (own work + ghosts x mean "
           "work), work = 1 + half a particle's pairs, c = the one-process step here over the "
           "total work; exchange = 2 x neighbouring ranks x latency + (ghosts sent + received) x "
           "120 B / bandwidth; the step = the slowest rank's compute + exchange + the rebuild "
           "decision's reduction, 2 x latency x ceil(log2 R). Slabs as dem run --mpi cuts them "
           "(the start's work). Weak scaling: R copies of the scene stacked along the slab axis, "
           "one per rank. Not modelled: the neighbour-list rebuilds' and migrations' extra cost, "
           "waiting caused by run-time imbalance, memory bandwidth shared by a node's ranks, "
           "network contention."}};
      write_json(json_out_, doc);
    }
    return 0;
  }
};

}  // namespace

void add_emulate_dem_mpi_command(CLI::App& emulate_app, const std::string& command_line,
                                 std::function<int()>& run) {
  auto command = std::make_shared<EmulateDemMpiCommand>();
  command->command_line_ = command_line;
  CLI::App* app = emulate_app.add_subcommand(
      "dem-mpi",
      "dem run --mpi over 1..1024 ranks, strong and weak: slabs' work and a network model");
  command->state_.add_to(*app);
  app->add_option("--ranks", command->ranks_, "rank counts (1,2,4,...,1024)");
  app->add_option("--steps", command->steps_, "steps timed in one process (100)");
  command->network_.add_to(*app);
  app->add_option("--measured", command->measured_,
                  "a scripts/dem-mpi-compare result file to check the prediction against");
  app->add_option("--json", command->json_out_, "write the document");
  run = [command, app]() -> int { return *app ? command->run() : -1; };
}

}  // namespace contactlab::cli
