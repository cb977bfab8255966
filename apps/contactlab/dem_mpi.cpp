// `dem run --mpi` (dem_mpi.hpp).
#include "dem_mpi.hpp"

#include <fmt/core.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <vector>

#include "cli_shared.hpp"
#include "contactlab/dem/checkpoint.hpp"
#include "contactlab/dem/config.hpp"
#include "contactlab/dem/engine.hpp"
#include "contactlab/dem/slabs.hpp"
#include "contactlab/dem_mpi/checkpoint.hpp"
#include "contactlab/dem_mpi/halo_exchange.hpp"
#include "contactlab/dem_mpi/start.hpp"
#include "contactlab/kernels/atomic_file.hpp"
#include "contactlab/kernels/error.hpp"
#include "contactlab/mpi/runtime.hpp"
#include "contactlab/tuner/context.hpp"
#include "dem_run_watch.hpp"
#include "mpi_errors.hpp"

namespace contactlab::cli {
namespace {

namespace dem = contactlab::dem;
namespace tn = contactlab::tuner;

// One rank's account of the run, gathered on rank 0.
struct RankAccount {
  double owned = 0, ghosts = 0, neighbor_s = 0, force_s = 0, integrate_s = 0, refresh_s = 0,
         migration_s = 0, wait_s = 0, migrated = 0, messages = 0, peak_rss_bytes = 0;
};
constexpr int kAccountFields = 11;

std::vector<RankAccount> gather_accounts(MPI_Comm comm, const RankAccount& mine) {
  const int ranks = mpi::size_of(comm);
  std::vector<RankAccount> all(static_cast<std::size_t>(ranks));
  static_assert(sizeof(RankAccount) == kAccountFields * sizeof(double));
  MPI_Gather(&mine, kAccountFields, MPI_DOUBLE, all.data(), kAccountFields, MPI_DOUBLE, 0, comm);
  return all;
}

}  // namespace

int run_dem_mpi(const DemMpiRequest& request) {
  mpi::Session session(nullptr, nullptr);
  const MPI_Comm comm = MPI_COMM_WORLD;
  const int rank = mpi::rank_of(comm), ranks = mpi::size_of(comm);
  return with_agreed_errors(comm, [&] {
    dem::DemConfig config;
    dem::EngineSettings settings;
    std::optional<dem::Particles> all;         // rank 0's: every particle of the run
    std::optional<dem::PairList> all_pairs;    // rank 0's, --restart: the checkpoint's list
    std::optional<dem::Engine::State> resume;  // --restart: its time and counters
    int frames = 0;
    int axis = -1;
    std::unique_ptr<RunOutputs> outputs;  // rank 0's
    // Every rank reads the config (its settings); rank 0 alone makes the particles.
    mpi::run_checked(comm, [&] {
      request.check_options();
      if (!(request.rebalance_margin >= 0)) {
        throw InputError("--rebalance-margin must be a fraction >= 0 (inf: never)");
      }
      if (request.until_discharged < 0 || request.until_discharged > 1) {
        throw InputError("--until-discharged must be a fraction in (0, 1]");
      }
      axis = request.axis.empty() ? -1 : dem::parse_axis(request.axis);
      if (!request.json_out.empty() && rank == 0) prepare_output_file(request.json_out);
      config = dem::read_dem_config(request.config);
      settings = config.settings;
      settings.threads = resolve_threads(request.threads);
      if (settings.threads < 1) throw InputError("--threads must be >= 0");
      if (!request.variant.empty()) {
        settings.force_variant = dem::parse_force_variant(request.variant);
      }
      if (request.until_discharged > 0 &&
          !(settings.sink_below_z > -std::numeric_limits<double>::infinity())) {
        throw InputError("--until-discharged needs a config with a sink");
      }
      if (rank != 0) return;
      all = dem::make_particles(config);
      outputs = std::make_unique<RunOutputs>(request.outputs, config, *all);
      // --resume: rank 0 alone looks for the file (the others never read it).
      const bool resuming = !request.resume.empty() && std::filesystem::exists(request.resume);
      const std::string& restart = resuming ? request.resume : request.restart;
      if (restart.empty()) return;
      // A checkpoint of any run: its particles and list weigh the slabs, its springs are
      // carried into each rank's first list, its counters go on (rank 0 holds the sums).
      all->set_wall_count(settings.walls.size());
      dem::CheckpointParts parts = dem::read_checkpoint_parts(restart, *all);
      all = std::move(parts.particles);
      all_pairs = std::move(parts.pairs);
      resume = parts.state;
      frames = parts.frames;
      outputs->continue_series(resume->time_s, frames);
      if (resuming) {
        fmt::print("resuming from {}: step {}, t = {:.6g} s\n", request.resume, resume->step,
                   resume->time_s);
      }
    });
    // The checkpoint's time and counters on every rank (the sums on rank 0 only).
    int resuming = resume ? 1 : 0;
    MPI_Bcast(&resuming, 1, MPI_INT, 0, comm);
    if (resuming != 0) {
      if (rank != 0) resume.emplace();
      MPI_Bcast(&*resume, sizeof(dem::Engine::State), MPI_BYTE, 0, comm);
      if (rank != 0) {
        resume->large_overlaps = 0;
        resume->initial_energy = 0.0;
        resume->removed_count = 0;
        resume->removed_mass = 0.0;
      }
    }
    dem::mpi::RankStart start = dem::mpi::deal_start(
        comm, all ? &*all : nullptr, all_pairs ? &*all_pairs : nullptr, settings, axis);
    all.reset();
    all_pairs.reset();
    const dem::SlabPlan& plan = start.plan;
    const std::uint64_t particles = start.particles;
    settings.skin = plan.skin;  // every rank the same, from all the particles
    dem::mpi::HaloExchange halo(comm, plan.slabs, plan.halo, request.rebalance_margin);
    halo.seed_springs(std::move(start.springs));
    // From here every failure may leave other ranks in a collective: it aborts them all.
    std::unique_ptr<dem::Engine> engine;
    try {
      engine = std::make_unique<dem::Engine>(settings, std::move(start.own), &halo,
                                             resume ? &*resume : nullptr);
    } catch (const std::exception& e) {
      mpi::abort_all(comm, e.what(), 2);
    }
    // --steps N from where the run stands, --until-time, or to the config's end.
    const std::uint64_t total_steps =
        last_step_of_run(engine->step_count(), engine->time_s(), settings.dt_s, request.steps,
                         request.until_time_s, config.end_time_s);
    const double start_mass = halo.sum_over_ranks([&] {
      double m = 0.0;
      for (std::size_t a = 0; a < engine->particles().size(); ++a) {
        if (!halo.is_ghost(a)) m += engine->particles().mass[a];
      }
      return m;
    }()) + halo.sum_over_ranks(engine->removed_mass());  // a restart's sink went before
    const double stop_mass = request.until_discharged * start_mass;
    if (rank == 0) {
      fmt::print(
          "dem run '{}' --mpi: {} particles over {} ranks x {} threads, slabs along {}{} "
          "(imbalance {:.3f} at the start), halo {:.4g} m; dt = {:.6g} s, steps {} -> {}\n",
          config.name, particles, ranks, settings.threads, dem::axis_name(plan.slabs.axis),
          plan.slabs.periodic ? " (periodic)" : "", plan.load.imbalance, plan.halo, settings.dt_s,
          engine->step_count(), total_steps);
    }
    // As one process: the steps between outputs run as one batch; with --until-discharged each
    // batch ends at a rebuild (the only step the sink takes particles), where the discharged
    // mass is summed over the ranks. At every output step rank 0 writes the gathered run.
    const auto end =
        stop_mass > 0 ? dem::Engine::BatchEnd::kAtRebuild : dem::Engine::BatchEnd::kAfterSteps;
    const std::uint64_t first_step = engine->step_count();
    const DemOutputOptions& asked = request.outputs;
    const bool frames_or_rows =
        !asked.vtk_dir.empty() || !asked.png_dir.empty() || !asked.discharge.empty();
    const bool checkpoints = !asked.checkpoint.empty() || !asked.vtk_dir.empty();
    double output_s = 0.0;
    // The frame and rows (with_frame) and the checkpoint (with_checkpoint) of the gathered run.
    auto output = [&](bool with_checkpoint, bool with_frame = true) {
      with_frame = with_frame && frames_or_rows;
      with_checkpoint = with_checkpoint && checkpoints;
      if (!with_frame && !with_checkpoint) return;
      const double began = omp_get_wtime();
      dem::mpi::GatheredRun run = dem::mpi::gather_run(comm, *engine, halo);
      if (with_frame) {
        mpi::run_checked(comm, [&] {
          if (outputs) outputs->write(run.snapshot(settings));
        });
      }
      if (with_checkpoint) {
        const int written = outputs ? outputs->frames() : 0;  // rank 0's count is the one written
        dem::mpi::write_checkpoint(comm, *engine, halo, std::move(run), written,
                                   outputs ? outputs->checkpoint() : std::string());
      }
      output_s += omp_get_wtime() - began;
    };
    // --resume and --progress as in one process; rank 0's clock and batch length rule, and a
    // signal on any rank stops every rank after the same batch.
    const bool resumable = !request.resume.empty();
    const bool watched = resumable || request.progress_every_s > 0;
    const OutputCadence cadence(config.output_every_s, settings.dt_s, first_step, total_steps,
                                resumable, request.steps == 0 && !request.until_time_s);
    const bool has_sink = settings.sink_below_z > -std::numeric_limits<double>::infinity();
    auto standing = [&] {  // collective when watched
      return RunWatch::Standing{
          engine->step_count(), engine->time_s(),
          halo.sum_over_ranks(static_cast<double>(engine->particle_steps())),
          has_sink ? halo.sum_over_ranks(engine->removed_mass()) / start_mass : -1.0};
    };
    RunWatch watch({.progress_every_s = rank == 0 ? request.progress_every_s : 0.0,
                    .terminal = false,
                    .checkpoint_every_s = resumable ? request.resume_every_s : 0.0,
                    .stop_on_signal = resumable},
                   watched ? standing() : RunWatch::Standing{}, total_steps);
    MPI_Barrier(comm);
    const double t0 = omp_get_wtime();
    double discharged = 0.0;
    try {
      if (engine->step_count() == 0) output(false);
      while (engine->step_count() < total_steps) {
        const std::uint64_t to_output = cadence.steps_to_next(engine->step_count());
        std::uint64_t batch =
            watch.batch_steps(std::min(to_output, total_steps - engine->step_count()));
        if (watched) MPI_Bcast(&batch, 1, MPI_UINT64_T, 0, comm);
        engine->run_steps(batch, end);
        // {a signal's number, rank 0's checkpoint clock}, agreed over the ranks.
        int requested[2] = {0, 0};
        if (watched) {
          watch.after_batch(standing());
          requested[0] = watch.stop_signal();
          requested[1] = rank == 0 && watch.checkpoint_due() ? 1 : 0;
          MPI_Allreduce(MPI_IN_PLACE, requested, 2, MPI_INT, MPI_MAX, comm);
        }
        const bool empty = engine->run_particles() == 0;
        if (stop_mass > 0) discharged = halo.sum_over_ranks(engine->removed_mass());
        const bool stop = stop_mass > 0 && discharged >= stop_mass;
        if (cadence.frame_at(engine->step_count(), empty || stop)) {
          output(true);
          watch.checkpoint_written();
        } else if (requested[0] != 0 || requested[1] != 0 ||
                   cadence.checkpoint_only_at(engine->step_count())) {
          output(true, false);
          watch.checkpoint_written();
        }
        if (requested[0] != 0) {
          if (rank == 0) {
            print_stopped_by_signal(requested[0], engine->step_count(), engine->time_s(),
                                    outputs->checkpoint());
          }
          return 128 + requested[0];
        }
        if (empty && rank == 0) {
          fmt::print("every particle has left through the sink by t = {:.6g} s: stopping\n",
                     engine->time_s());
        }
        if (stop && rank == 0) {
          fmt::print(
              "the sink has taken {:.6g} kg of {:.6g} kg (--until-discharged {:g}) by t = {:.6g} "
              "s: stopping\n",
              discharged, start_mass, request.until_discharged, engine->time_s());
        }
        if (empty || stop) break;
      }
      mpi::run_checked(comm, [&] {
        if (outputs) outputs->finish();
      });
    } catch (const std::exception& e) {
      mpi::abort_all(comm, e.what(), 4);
    }
    const double wall = omp_get_wtime() - t0;
    watch.finish(wall, engine->step_count() == total_steps);
    if (rank == 0 && checkpoints) fmt::print("wrote {}\n", outputs->checkpoint());
    discharged = halo.sum_over_ranks(engine->removed_mass());
    const double particle_steps =
        halo.sum_over_ranks(static_cast<double>(engine->particle_steps()));
    const dem::Energies energy = engine->energies();
    const dem::PhaseTimes& ph = engine->phase_times();
    const dem::mpi::HaloStats& hs = halo.stats();
    const RankAccount mine{static_cast<double>(halo.owned_count()),
                           static_cast<double>(hs.ghosts),
                           ph.neighbor_s,
                           ph.force_s(),
                           ph.integrate_s,
                           hs.refresh_s,
                           hs.migration_s,
                           hs.agreement_s,
                           static_cast<double>(hs.migrated),
                           static_cast<double>(hs.messages),
                           static_cast<double>(mpi::peak_rss_bytes())};
    const std::vector<RankAccount> accounts = gather_accounts(comm, mine);
    mpi::run_checked(comm, [&] {
      if (rank != 0) return;
      fmt::print(
          "done: t = {:.6g} s, {} steps in {:.3f} s ({:.3g} particle-steps/s over all ranks), "
          "{} rebuilds, step on {}{}\n",
          engine->time_s(), engine->step_count() - first_step, wall,
          particle_steps / std::max(wall, 1e-9), engine->rebuilds(),
          dem::to_string(engine->instruction_set()),
          output_s > 0 ? fmt::format("; {:.3f} s of it gathering and writing outputs", output_s)
                       : "");
      fmt::print("{:>5} {:>9} {:>8} {:>10} {:>10} {:>10} {:>10} {:>10} {:>10} {:>9} {:>8}\n",
                 "rank", "owned", "ghosts", "forces s", "list s", "integr. s", "halo s",
                 "migrate s", "waits s", "migrated", "peak MB");
      double force_max = 0.0, force_sum = 0.0;
      nlohmann::json rows = nlohmann::json::array();
      for (int r = 0; r < ranks; ++r) {
        const RankAccount& a = accounts[r];
        fmt::print(
            "{:>5} {:>9} {:>8} {:>10.3f} {:>10.3f} {:>10.3f} {:>10.3f} {:>10.3f} "
            "{:>10.3f} {:>9} {:>8.0f}\n",
            r, a.owned, a.ghosts, a.force_s, a.neighbor_s, a.integrate_s, a.refresh_s,
            a.migration_s, a.wait_s, a.migrated, a.peak_rss_bytes / 1e6);
        force_max = std::max(force_max, a.force_s);
        force_sum += a.force_s;
        rows.push_back(
            {{"rank", r},
             {"owned_at_end", a.owned},
             {"ghosts_at_end", a.ghosts},
             {"forces_s", a.force_s},
             {"neighbor_list_s", a.neighbor_s},
             {"integration_s", a.integrate_s},
             {"ghost_exchange_s", a.refresh_s},
             {"migration_s", a.migration_s},
             {"agreement_wait_s", a.wait_s},
             {"migrated", a.migrated},
             {"messages", a.messages},
             {"peak_rss_bytes", a.peak_rss_bytes},
             {"slab_lo_m", std::isfinite(plan.slabs.cuts[r]) ? nlohmann::json(plan.slabs.cuts[r])
                                                             : nlohmann::json()},
             {"slab_hi_m", std::isfinite(plan.slabs.cuts[r + 1])
                               ? nlohmann::json(plan.slabs.cuts[r + 1])
                               : nlohmann::json()}});
      }
      const double force_imbalance = force_sum > 0 ? force_max / (force_sum / ranks) : 1.0;
      fmt::print(
          "work imbalance at the rebuilds (largest rank / mean): mean {:.3f}, largest {:.3f} "
          "over {} rebuilds; re-balanced {} times (margin {:g})\n",
          hs.imbalance_mean(), hs.imbalance_max, hs.imbalance_samples, hs.rebalances,
          request.rebalance_margin);
      fmt::print(
          "force time imbalance (slowest / mean): {:.3f}; energy [J]: kinetic {:.6g}, potential "
          "{:.6g}, dissipated {:.6g}\n",
          force_imbalance, energy.kinetic, energy.potential, energy.dissipated);
      if (discharged > 0) {
        fmt::print("discharged: {:.6g} kg; {} particles left\n", discharged,
                   engine->run_particles());
      }
      if (request.json_out.empty()) return;
      const nlohmann::json doc{
          {"schema_version", 1},
          {"kind", "contactlab-dem-mpi-run"},
          {"context", tn::collect_context(request.command_line, settings.threads)},
          {"config", config.name},
          {"particles", particles},
          {"ranks", ranks},
          {"threads_per_rank", settings.threads},
          {"axis", dem::axis_name(plan.slabs.axis)},
          {"halo_m", plan.halo},
          {"start_imbalance", plan.load.imbalance},
          {"steps", engine->step_count()},
          {"time_s", engine->time_s()},
          {"wall_s", wall},
          {"output_s", output_s},
          {"force_variant", dem::to_string(settings.force_variant)},
          {"instruction_set", dem::to_string(engine->instruction_set())},
          {"particle_steps_per_s", particle_steps / std::max(wall, 1e-9)},
          {"rebuilds", engine->rebuilds()},
          {"force_imbalance", force_imbalance},
          {"work_imbalance",
           {{"mean", hs.imbalance_mean()},
            {"largest", hs.imbalance_max},
            {"rebuilds", hs.imbalance_samples},
            {"rebalances", hs.rebalances},
            {"margin", std::isfinite(request.rebalance_margin)
                           ? nlohmann::json(request.rebalance_margin)
                           : nlohmann::json("never")}}},
          {"discharged_kg", discharged},
          {"particles_left", engine->run_particles()},
          {"energy_j",
           {{"kinetic", energy.kinetic},
            {"potential", energy.potential},
            {"dissipated", energy.dissipated}}},
          {"per_rank", rows}};
      write_json(request.json_out, doc);
    });
    return 0;
  });
}

}  // namespace contactlab::cli
