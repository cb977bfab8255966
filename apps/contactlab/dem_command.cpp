// `contactlab dem run|validate|timestep`: DEM runs from a JSON config (VTK frames, energy CSV,
// discharge CSV, section pictures, checkpoints), the validation cases as a table, and the
// time-step study (`dem variants` and `dem profile`: dem_study_command.cpp).
#include <fmt/core.h>
#include <omp.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "cli_shared.hpp"
#include "contactlab/dem/checkpoint.hpp"
#include "contactlab/dem/config.hpp"
#include "contactlab/dem/discharge.hpp"
#include "contactlab/dem/timestep_study.hpp"
#include "contactlab/dem/validation.hpp"
#include "contactlab/kernels/atomic_file.hpp"
#include "contactlab/kernels/detector.hpp"
#include "contactlab/kernels/error.hpp"
#include "contactlab/tuner_dem/force_model.hpp"
#include "dem_mpi.hpp"
#include "dem_outputs.hpp"
#include "dem_run_watch.hpp"
#include "dem_start.hpp"
#include "dem_variant_tuning.hpp"

namespace contactlab::cli {
namespace {

namespace dem = contactlab::dem;

struct DemRunCommand {
  std::string config_;
  int threads_ = 0;
  std::string variant_;
  std::string vtk_dir_;
  std::string png_dir_;
  std::string discharge_;
  std::string restart_;
  std::string checkpoint_;
  std::uint64_t steps_ = 0;
  std::optional<double> until_time_;
  double until_discharged_ = 0.0;
  std::string resume_;
  double resume_every_s_ = 600.0;
  double progress_every_s_ = 0.0;
  bool retune_ = false;
  double retune_margin_ = 0.05;
  std::uint64_t calibration_steps_ = 50;
  std::string variant_log_;
  bool mpi_ = false;
  std::string axis_;
  double rebalance_margin_ = 0.1;
  std::string json_out_;
  std::string command_line_;

  DemOutputOptions output_options() const {
    return {vtk_dir_, png_dir_, discharge_, resume_.empty() ? checkpoint_ : resume_};
  }

  // --mpi: the run decomposed over the processes (dem_mpi.cpp). The force model behind
  // --variant auto is calibrated on one process's run: it is refused by name.
  int run_mpi() const {
    DemMpiRequest request;
    request.config = config_;
    request.threads = threads_;
    request.steps = steps_;
    request.until_time_s = until_time_;
    request.until_discharged = until_discharged_;
    request.axis = axis_;
    request.rebalance_margin = rebalance_margin_;
    request.variant = variant_;
    request.json_out = json_out_;
    request.outputs = output_options();
    request.restart = restart_;
    request.resume = resume_;
    request.resume_every_s = resume_every_s_;
    request.progress_every_s = progress_every_s_;
    request.command_line = command_line_;
    request.check_options = [this] {
      const std::pair<bool, const char*> unsupported[] = {{variant_ == "auto", "--variant auto"},
                                                          {retune_, "--retune"},
                                                          {!variant_log_.empty(), "--variant-log"}};
      for (const auto& [given, name] : unsupported) {
        if (given) {
          throw InputError(std::string(name) +
                           " is not available with --mpi (the force model is calibrated in one "
                           "process): give --variant a name");
        }
      }
      check_stopping_and_resuming();
    };
#ifdef CONTACTLAB_HAVE_MPI
    return run_dem_mpi(request);
#else
    throw InputError("this contactlab was built without MPI (dem run --mpi)");
#endif
  }

  // --steps, --until-time, --resume and their companions, before any work.
  void check_stopping_and_resuming() const {
    if (steps_ > 0 && until_time_) throw InputError("--steps and --until-time: give one of them");
    if (until_time_ && !(*until_time_ >= 0.0)) throw InputError("--until-time must be >= 0");
    if (!resume_.empty() && (!restart_.empty() || !checkpoint_.empty())) {
      throw InputError(std::string("--resume and ") +
                       (!restart_.empty() ? "--restart" : "--checkpoint") +
                       ": give one of them (--resume restarts from its file and writes it)");
    }
    if (!(resume_every_s_ > 0.0)) throw InputError("--resume-every must be > 0 seconds");
    if (!(progress_every_s_ >= 0.0)) throw InputError("--progress must be >= 0 seconds");
  }

  int run() const {
    if (mpi_) return run_mpi();
    if (!axis_.empty() || !json_out_.empty()) {
      throw InputError(std::string(!axis_.empty() ? "--axis" : "--json") + " needs --mpi");
    }
    const dem::DemConfig config = dem::read_dem_config(config_);
    dem::EngineSettings settings = config.settings;
    settings.threads = resolve_threads(threads_);
    if (settings.threads < 1) throw InputError("--threads must be >= 0");
    const bool auto_variant = variant_ == "auto";
    if (!variant_.empty() && !auto_variant) {
      settings.force_variant = dem::parse_force_variant(variant_);
    }
    if (retune_ && !auto_variant) throw InputError("--retune needs --variant auto");
    if (retune_margin_ < 0) throw InputError("--retune-margin must be >= 0");
    if (auto_variant && calibration_steps_ == 0) {
      throw InputError("--calibration-steps must be >= 1");
    }
    const bool has_sink = settings.sink_below_z > -std::numeric_limits<double>::infinity();
    if (until_discharged_ < 0 || until_discharged_ > 1) {
      throw InputError("--until-discharged must be a fraction in (0, 1]");
    }
    if (until_discharged_ > 0 && !has_sink) {
      throw InputError("--until-discharged needs a config with a sink");
    }
    check_stopping_and_resuming();
    // --resume FILE: continue from FILE where an earlier run of this command left it.
    const bool resuming = !resume_.empty() && std::filesystem::exists(resume_);
    const std::string& restart = resuming ? resume_ : restart_;
    // Output folders are made, and output paths checked, before any work.
    if (!variant_log_.empty()) prepare_output_file(variant_log_);
    dem::Particles initial = dem::make_particles(config);
    RunOutputs outputs(output_options(), config, initial);
    // --variant auto: the force model calibrated on this run's start (a few short runs from
    // copies of it), then the variant it predicts fastest; --retune re-prices at each rebuild.
    std::unique_ptr<VariantTuning> tuning;
    if (auto_variant) {
      DemStart start;
      start.restart = restart;
      tuning = std::make_unique<VariantTuning>(
          dem::calibrate_force_costs([&](const dem::ForceVariant& v,
                                         int t) { return start.engine(config, initial, v, t); },
                                     settings.threads, calibration_steps_),
          retune_margin_);
    }
    dem::Engine engine(settings, std::move(initial));
    if (!restart.empty()) {
      const int frames = dem::read_checkpoint(engine, restart);
      outputs.continue_series(engine.time_s(), frames);
      if (resuming) {
        fmt::print("resuming from {}: step {}, t = {:.6g} s\n", resume_, engine.step_count(),
                   engine.time_s());
      }
    }
    const double dt = settings.dt_s;
    // Steps from where the (restarted) run stands (a restart may change dt).
    const std::uint64_t total_steps = last_step_of_run(engine.step_count(), engine.time_s(), dt,
                                                       steps_, until_time_, config.end_time_s);
    fmt::print(
        "dem run '{}': {} particles, {} walls, dt = {:.6g} s (stable limit {:.6g} s), "
        "steps {} -> {}, {} threads{}\n",
        config.name, engine.particles().size(), settings.walls.size(), dt, engine.stable_dt(),
        engine.step_count(), total_steps, settings.threads,
        has_sink ? fmt::format(", sink below z = {:.6g} m", settings.sink_below_z) : "");
    const std::string& checkpoint = outputs.checkpoint();
    auto output = [&] { outputs.write(engine.snapshot()); };
    if (engine.step_count() == 0) output();
    if (tuning) tuning->start(engine);
    // --until-discharged F: the mass the sink must have taken (of all the run started with).
    double start_mass = engine.removed_mass();
    for (const double m : engine.particles().mass) start_mass += m;
    const double stop_mass = until_discharged_ * start_mass;
    const double t0 = omp_get_wtime();
    const std::uint64_t first_step = engine.step_count();
    const std::uint64_t first_particle_steps = engine.particle_steps();
    const OutputCadence cadence(config.output_every_s, dt, first_step, total_steps,
                                !resume_.empty(), steps_ == 0 && !until_time_);
    auto standing = [&] {
      return RunWatch::Standing{engine.step_count(), engine.time_s(),
                                static_cast<double>(engine.particle_steps()),
                                has_sink ? engine.removed_mass() / start_mass : -1.0};
    };
    RunWatch watch({.progress_every_s = progress_every_s_,
                    .terminal = ::isatty(STDERR_FILENO) != 0,
                    .checkpoint_every_s = resume_.empty() ? 0.0 : resume_every_s_,
                    .stop_on_signal = !resume_.empty()},
                   standing(), total_steps);
    auto write_checkpoint = [&] {
      if (checkpoint.empty()) return;
      dem::write_checkpoint(engine, outputs.frames(), checkpoint);
      watch.checkpoint_written();
    };
    // Between outputs the steps run as one batch (each finish drifts the next step). The
    // re-tuner and --until-discharged look after each neighbour-list rebuild (the only step that
    // changes the pair list or the discharged mass): their batches end there.
    const auto end = (tuning && retune_) || stop_mass > 0 ? dem::Engine::BatchEnd::kAtRebuild
                                                          : dem::Engine::BatchEnd::kAfterSteps;
    try {
      while (engine.step_count() < total_steps) {
        const std::uint64_t to_output = cadence.steps_to_next(engine.step_count());
        engine.run_steps(watch.batch_steps(std::min(to_output, total_steps - engine.step_count())),
                         end);
        if (tuning && retune_) tuning->after_steps(engine);
        watch.after_batch(standing());
        const bool empty = engine.particles().size() == 0;
        if (cadence.frame_at(engine.step_count(), empty)) {
          output();
          write_checkpoint();
        } else if (watch.checkpoint_due() || cadence.checkpoint_only_at(engine.step_count())) {
          write_checkpoint();
        }
        if (const int signal = watch.stop_signal()) {
          write_checkpoint();
          print_stopped_by_signal(signal, engine.step_count(), engine.time_s(), checkpoint);
          return 128 + signal;
        }
        if (empty) {
          fmt::print("every particle has left through the sink by t = {:.6g} s: stopping\n",
                     engine.time_s());
          break;
        }
        if (stop_mass > 0 && engine.removed_mass() >= stop_mass) {
          output();
          write_checkpoint();
          fmt::print(
              "the sink has taken {:.6g} kg of {:.6g} kg (--until-discharged {:g}) by t = "
              "{:.6g} s: stopping\n",
              engine.removed_mass(), start_mass, until_discharged_, engine.time_s());
          break;
        }
      }
    } catch (const dem::UnstableRun& e) {
      fmt::print(stderr, "contactlab: error: unstable run: {}\n", e.what());
      return 4;
    }
    outputs.finish();
    const double wall = omp_get_wtime() - t0;
    watch.finish(wall, engine.step_count() == total_steps);
    const double steps = static_cast<double>(engine.step_count() - first_step);
    const dem::Energies e = engine.energies();
    const dem::PhaseTimes& ph = engine.phase_times();
    fmt::print(
        "done: t = {:.6g} s, {} steps in {:.3f} s ({:.3g} particle-steps/s), {} rebuilds, {} "
        "choices of the near pairs, step on {}\n",
        engine.time_s(), steps, wall,
        static_cast<double>(engine.particle_steps() - first_particle_steps) / std::max(wall, 1e-9),
        engine.rebuilds(), engine.near_builds(), dem::to_string(engine.instruction_set()));
    fmt::print(
        "phases [s]: neighbour list {:.3f}, pair forces {:.3f}, reduction {:.3f}, serial walls "
        "{:.3f}, update {:.3f}, integration {:.3f}\n",
        ph.neighbor_s, ph.pair_forces_s, ph.reduction_s, ph.walls_s, ph.update_s, ph.integrate_s);
    fmt::print("energy [J]: kinetic {:.6g}, potential {:.6g}, dissipated {:.6g}\n", e.kinetic,
               e.potential, e.dissipated);
    if (has_sink) {
      const dem::DischargeRow row = dem::discharge_row(engine.snapshot());
      fmt::print("discharged: {:.6g} kg in {} particles, {} left\n", row.discharged_kg,
                 row.discharged, row.left);
    }
    if (tuning) {
      tuning->finish(engine, wall);
      if (!variant_log_.empty()) tuning->write_log(variant_log_);
    }
    if (engine.large_overlap_count() > 0) {
      fmt::print("overlaps above 1 % of the smaller diameter: {} contact-steps\n",
                 engine.large_overlap_count());
    }
    return 0;
  }
};

struct DemValidateCommand {
  std::string only_;
  std::string variant_;
  int threads_ = 1;
  int run() const {
    if (threads_ < 0) throw InputError("--threads must be >= 0");
    dem::set_validation_engine(
        variant_.empty() ? dem::ForceVariant{} : dem::parse_force_variant(variant_),
        resolve_threads(threads_));
    fmt::print("{:<58} {:<34} {:>13} {:>13} {:>10} {:>9}  {}\n", "case", "quantity", "expected",
               "measured", "error", "tolerance", "result");
    bool all = true;
    int ran = 0;
    for (const dem::ValidationCase& c : dem::validation_cases()) {
      if (!only_.empty() && c.name != only_) continue;
      ++ran;
      for (const dem::ValidationRow& r : c.run()) {
        all = all && r.pass;
        fmt::print("{:<58} {:<34} {:>13.6g} {:>13.6g} {:>9.3g}{} {:>9.3g}  {}  {}\n", r.case_name,
                   r.quantity, r.expected, r.measured, r.error, r.relative ? "r" : "a", r.tolerance,
                   r.pass ? "pass" : "FAIL", r.note);
      }
    }
    if (ran == 0) throw InputError("no validation case named '" + only_ + "'");
    fmt::print("\nerror: r = relative, a = absolute; the step on {}. {}\n",
               dem::to_string(dem::step_isa()), all ? "All cases pass." : "FAILURES.");
    return all ? 0 : 1;
  }
};

struct DemTimestepCommand {
  std::string config_;
  std::uint64_t steps_ = 100;
  int threads_ = 0;
  int run() const {
    const dem::DemConfig config = dem::read_dem_config(config_);
    dem::EngineSettings settings = config.settings;
    settings.threads = resolve_threads(threads_);
    const dem::Particles particles = dem::make_particles(config);
    const dem::TimestepStudy study = dem::timestep_study(settings, particles, steps_);
    fmt::print(
        "contact time t_c (lightest pair) {:.6g} s\nstable limit {:.6g} s ({:.3f} t_c)\n"
        "recommended dt = t_c/50 = {:.6g} s (config: {:.6g} s)\n\n",
        study.contact_time_s, study.stable_dt_s, study.stable_dt_s / study.contact_time_s,
        study.recommended_dt_s, settings.dt_s);
    fmt::print("{:>8} {:>12} {:>22} {:>14} {:>14} {:>14}\n", "dt", "dt [s]", "wall s / simulated s",
               "|de| sync", "|de| half-step", "|1-e^2| e=1");
    for (const dem::TimestepRow& r : study.rows) {
      const std::string wall = r.wall_per_simulated_s < 0
                                   ? std::string("refused")
                                   : fmt::format("{:.4g}", r.wall_per_simulated_s);
      fmt::print("{:>8} {:>12.4g} {:>22} {:>14.3g} {:>14.3g} {:>14.3g}\n",
                 fmt::format("t_c/{:g}", r.divisor), r.dt_s, wall, r.e_error_synchronised,
                 r.e_error_half_step, r.energy_error);
    }
    fmt::print(
        "\nwall time from {} steps of the config's scene on {} threads; errors from a "
        "head-on impact of two of its smallest spheres (e vs the clamp-predicted value)\n",
        steps_, settings.threads);
    return 0;
  }
};

}  // namespace

Subcommand add_dem_command(CLI::App& app, const std::string& command_line) {
  CLI::App* sub = app.add_subcommand("dem", "DEM: run a config, validate the engine, study dt");
  sub->require_subcommand(1);
  auto run = std::make_shared<DemRunCommand>();
  run->command_line_ = command_line;
  CLI::App* run_app = sub->add_subcommand("run", "run a DEM config");
  run_app->add_option("config", run->config_, "DEM config (JSON, docs/dem.md)")->required();
  run_app->add_option("--threads", run->threads_, "OpenMP threads (0 = OpenMP's default)");
  run_app->add_option("--variant", run->variant_,
                      "force variant, e.g. per-thread/dynamic,4 (default ordered/static), or auto: "
                      "the force model's choice (calibrated on the run's start)");
  run_app->add_flag("--retune", run->retune_,
                    "with --variant auto: re-price the variants at each neighbour-list rebuild "
                    "and switch when the predicted gain exceeds the margin");
  run_app->add_option(
      "--retune-margin", run->retune_margin_,
      "predicted gain needed to leave the running variant, the config's at the start "
      "(fraction, default 0.05)");
  run_app->add_option("--calibration-steps", run->calibration_steps_,
                      "--variant auto: timed steps per calibration run (50)");
  run_app->add_option("--variant-log", run->variant_log_,
                      "--variant auto: CSV of which variant ran when (step, time, variant, "
                      "predicted gain)");
  run_app->add_option("--vtk", run->vtk_dir_, "write DIR/<name>.pvd, frames, energy CSV, last.chk");
  run_app->add_option("--png", run->png_dir_,
                      "write DIR/<name>_section_NNNNN.png per frame and DIR/<name>_discharge.png");
  run_app->add_option(
      "--discharge", run->discharge_,
      "discharge CSV (default with a sink: DIR/<name>_discharge.csv of --vtk/--png)");
  run_app->add_option("--steps", run->steps_,
                      "run N steps from where the run stands (default 0: to the config's end)");
  run_app->add_option("--restart", run->restart_, "continue from a checkpoint of this config");
  run_app->add_option("--until-time", run->until_time_,
                      "run up to this simulated time [s] (absolute: a resumed run stops at the "
                      "same step), instead of the config's end");
  run_app->add_option("--resume", run->resume_,
                      "continue from this checkpoint when it exists, else start; it is written at "
                      "every output, every --resume-every seconds and on SIGINT/SIGTERM, so the "
                      "same command run again continues where the last one stopped");
  run_app->add_option("--resume-every", run->resume_every_s_,
                      "--resume: wall seconds between checkpoints (default 600)");
  run_app->add_option("--progress", run->progress_every_s_,
                      "a progress line on stderr at least every this many wall seconds (share "
                      "done, simulated time, rate, time left; a terminal shows a bar anyway)");
  run_app->add_option("--until-discharged", run->until_discharged_,
                      "stop once the sink has taken this fraction of the mass (e.g. 0.5)");
  run_app->add_flag("--mpi", run->mpi_,
                    "run decomposed over the MPI processes (under mpirun): slabs balanced by "
                    "work, ghosts exchanged every step, particles and their contact history "
                    "migrating at rebuilds");
  run_app->add_option("--axis", run->axis_, "--mpi: the slabs' axis x, y or z (default: longest)");
  run_app->add_option("--rebalance-margin", run->rebalance_margin_,
                      "--mpi: re-cut the slabs at a rebuild where the largest rank's work exceeds "
                      "the mean by this fraction (default 0.1; inf: never)");
  run_app->add_option("--json", run->json_out_,
                      "--mpi: write the run and every rank's phase times as JSON");
  run_app->add_option("--checkpoint", run->checkpoint_,
                      "checkpoint file written at every output (default: DIR/last.chk with --vtk; "
                      "with --mpi, the file one process would have written)");
  auto validate = std::make_shared<DemValidateCommand>();
  CLI::App* validate_app = sub->add_subcommand("validate", "run every validation case");
  validate_app->add_option("--case", validate->only_, "run only this case");
  validate_app->add_option("--variant", validate->variant_, "run the cases on this force variant");
  validate_app->add_option("--threads", validate->threads_, "threads of every case (default 1)");
  const std::vector<Subcommand> studies = add_dem_study_commands(*sub, command_line);
  auto timestep = std::make_shared<DemTimestepCommand>();
  CLI::App* timestep_app =
      sub->add_subcommand("timestep", "stable limit, recommended dt, speed against error");
  timestep_app->add_option("config", timestep->config_, "DEM config")->required();
  timestep_app->add_option("--steps", timestep->steps_, "steps of the scene timed per dt");
  timestep_app->add_option("--threads", timestep->threads_, "OpenMP threads");
  return {sub, [=] {
            if (*run_app) return run->run();
            if (*validate_app) return validate->run();
            for (const Subcommand& study : studies) {
              if (*study.app) return study.run();
            }
            return timestep->run();
          }};
}

}  // namespace contactlab::cli
