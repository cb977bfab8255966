// `contactlab dem profile`: the report's profile of a DEM step (Otsuka): the phase split at one
// thread against its 80/15/5, the serial fraction, the Amdahl bound it implies against the
// measured speed-up, and with --emulate the step at thread counts this machine does not have
// (tuner_dem/step_emulation.hpp), checked against the thread counts it has.
#include <fmt/core.h>
#include <omp.h>

#include <algorithm>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "cli_shared.hpp"
#include "contactlab/kernels/atomic_file.hpp"
#include "contactlab/kernels/error.hpp"
#include "contactlab/support/statistics.hpp"
#include "contactlab/tuner/bandwidth_probe.hpp"
#include "contactlab/tuner/context.hpp"
#include "contactlab/tuner/thread_emulation.hpp"
#include "contactlab/tuner_dem/force_model.hpp"
#include "contactlab/tuner_dem/step_emulation.hpp"
#include "contactlab/tuner_model/emulation.hpp"
#include "dem_start.hpp"

namespace contactlab::cli {
namespace {

namespace tn = contactlab::tuner;

double amdahl(double serial_fraction, int threads) {
  return 1.0 / (serial_fraction + (1.0 - serial_fraction) / threads);
}

// One thread count's rounds: wall seconds per step and the phases per step.
struct Rounds {
  int threads = 1;
  std::vector<double> step_s;
  std::vector<dem::PhaseTimes> phases;
  // The phase medians, phase by phase.
  dem::PhaseTimes median_phases() const {
    auto of = [&](double dem::PhaseTimes::*field) {
      std::vector<double> v;
      for (const dem::PhaseTimes& p : phases) v.push_back(p.*field);
      return median(v);
    };
    dem::PhaseTimes m;
    for (double dem::PhaseTimes::*f :
         {&dem::PhaseTimes::neighbor_s, &dem::PhaseTimes::pair_forces_s,
          &dem::PhaseTimes::reduction_s, &dem::PhaseTimes::walls_s, &dem::PhaseTimes::update_s,
          &dem::PhaseTimes::integrate_s}) {
      m.*f = of(f);
    }
    return m;
  }
};

struct DemProfileCommand {
  DemStart start_;
  std::string variant_ = "ordered/static";
  std::vector<int> emulate_;
  MemoryOptions memory_;
  int rounds_ = 1;
  std::string json_out_;
  std::string command_line_;
  int run() const;
};

int DemProfileCommand::run() const {
  const dem::DemConfig config = start_.checked_config();
  const dem::ForceVariant variant = dem::parse_force_variant(variant_);
  if (start_.threads.front() != 1) {
    throw InputError("--threads must start with 1 (the speed-ups are over one thread)");
  }
  if (rounds_ < 1) throw InputError("--rounds must be >= 1");
  for (const int t : emulate_) {
    if (t < 1) throw InputError("--emulate: every thread count must be >= 1");
  }
  if (!memory_.machine_file.empty() && emulate_.empty()) {
    throw InputError("--machine prices the emulation: give --emulate too");
  }
  const std::optional<tn::MemorySystem> memory = memory_.load();
  if (!json_out_.empty()) prepare_output_file(json_out_);
  const std::uint64_t steps = start_.steps;
  const dem::Particles particles = dem::make_particles(config);
  auto make_engine = [&](const dem::ForceVariant& v, int threads) {
    return start_.engine(config, particles, v, threads);
  };
  // Rounds interleave the thread counts, each from the same start, so that a slow spell of the
  // machine touches all of them alike.
  std::vector<Rounds> measured;
  for (const int t : start_.threads) measured.push_back({t, {}, {}});
  // The particles where the timed steps start: a restart's (a hopper's sink may have taken
  // many), not the config's.
  std::size_t count = 0;
  for (int round = 0; round < rounds_; ++round) {
    for (Rounds& m : measured) {
      const std::unique_ptr<dem::Engine> engine = make_engine(variant, m.threads);
      engine->step();  // untimed: first touches
      count = engine->particles().size();
      const dem::PhaseTimes before = engine->phase_times();
      const double t0 = omp_get_wtime();
      engine->run_steps(steps);
      m.step_s.push_back((omp_get_wtime() - t0) / static_cast<double>(steps));
      m.phases.push_back((engine->phase_times() - before) / static_cast<double>(steps));
    }
  }
  const dem::PhaseTimes one = measured.front().median_phases();
  const double one_step = median(measured.front().step_s);
  const double total = one.total_s();
  fmt::print("dem profile '{}': {} particles, variant {}, {} steps per run, {} round(s)\n\n",
             config.name, count, dem::to_string(variant), steps, rounds_);
  fmt::print("phase split at 1 thread (the report: forces 80 %, update 15 %, candidates 5 %)\n");
  const bool fused_ordered =
      variant.fused_update && variant.accumulation == dem::Accumulation::kOrdered;
  const std::pair<const char*, double> phases[] = {
      {"candidates (neighbour list)", one.neighbor_s},
      {fused_ordered ? "pair forces + reduction + update (fused)" : "pair forces",
       one.pair_forces_s},
      {"reduction", one.reduction_s},
      {"wall forces (serial)", one.walls_s},
      {variant.serial_walls ? "update" : "update (incl. wall forces)", one.update_s},
      {"integration", one.integrate_s}};
  for (const auto& [name, seconds] : phases) {
    fmt::print("  {:<42} {:>11.4g} s/step {:>6.1f} %\n", name, seconds, 100.0 * seconds / total);
  }
  // The serial part of the step at one thread: the serial walls, and of the neighbour-list
  // rebuild what did not shrink from one thread to the widest measured (serial + parallel / P
  // fitted to the two; every pass of the rebuild runs on the team since 2026-12-05, where the
  // whole rebuild had been counted). With one thread measured, or no rebuild timed at the
  // widest, the whole rebuild is counted: an upper bound on the serial part, so the bound below
  // is then a floor, and the line says so.
  const Rounds& widest =
      *std::max_element(measured.begin(), measured.end(),
                        [](const Rounds& a, const Rounds& b) { return a.threads < b.threads; });
  const double wide_list_s = widest.median_phases().neighbor_s;
  const bool rebuilt = one.neighbor_s > 0.0;
  const bool list_fitted = rebuilt && widest.threads > 1 && wide_list_s > 0.0;
  const double list_serial_s =
      list_fitted ? tn::AmdahlPhase::fit(one.neighbor_s, widest.threads, wide_list_s).serial_s
                  : std::max(one.neighbor_s, 0.0);
  const std::string serial_method =
      !rebuilt      ? std::string("no neighbour-list rebuild in the timed steps")
      : list_fitted ? fmt::format("the neighbour list's serial part, fitted from 1 and {} threads",
                                  widest.threads)
                    : std::string("the neighbour list counted whole: an upper bound");
  const double serial = (list_serial_s + one.walls_s) / total;
  fmt::print("\nserial fraction ({}, + serial walls, at 1 thread): {:.4f}\n", serial_method,
             serial);
  fmt::print("{:>7} {:>12} {:>24} {:>16} {:>9} {:>13} {:>12}\n", "threads", "s/step",
             "95% interval", "particle-steps/s", "speedup", "Amdahl bound", "Karp-Flatt e");
  nlohmann::json measured_json = nlohmann::json::array();
  for (const Rounds& m : measured) {
    const Summary s = summarize(m.step_s);
    const double speedup = one_step / s.median;
    const double p = m.threads;
    const std::string karp_flatt =
        m.threads > 1 ? fmt::format("{:.4f}", (1.0 / speedup - 1.0 / p) / (1.0 - 1.0 / p))
                      : std::string("-");
    fmt::print("{:>7} {:>12.4g} {:>24} {:>16.4g} {:>9.3f} {:>13.3f} {:>12}\n", m.threads, s.median,
               fmt::format("[{:.4g}, {:.4g}]", s.interval.low, s.interval.high),
               static_cast<double>(count) / s.median, speedup, amdahl(serial, m.threads),
               karp_flatt);
    // Each round's speed-up over its own one-thread run (the rounds interleave the thread
    // counts: a slow spell touches both sides of a ratio), beside the median's.
    std::vector<double> round_speedups;
    for (std::size_t r = 0; r < m.step_s.size(); ++r)
      round_speedups.push_back(measured.front().step_s[r] / m.step_s[r]);
    measured_json.push_back({{"threads", m.threads},
                             {"step_s", tn::interval_json(s)},
                             {"speedup", speedup},
                             {"round_step_s", m.step_s},
                             {"round_speedups", round_speedups}});
  }
  fmt::print("Amdahl bound at 2 / 8 / 16 threads: {:.2f} / {:.2f} / {:.2f}\n", amdahl(serial, 2),
             amdahl(serial, 8), amdahl(serial, 16));
  fmt::print(
      "(Karp-Flatt e: the serial fraction the measured speed-up implies, (1/S - 1/p)/(1 - "
      "1/p); above the structural one when the parallel part itself scales worse than p, "
      "e.g. memory bandwidth, load imbalance or a busy core)\n");

  nlohmann::json emulated_json = nlohmann::json::array(), checks = nlohmann::json::array();
  nlohmann::json bandwidth_json;  // null without --machine
  if (!emulate_.empty()) {
    // The model's costs at one thread, the pair list of the common start.
    const dem::ForceCosts costs = dem::calibrate_force_costs(make_engine, 1, steps);
    dem::ForceLoopWork work;
    {
      const std::unique_ptr<dem::Engine> at_start = make_engine(variant, 1);
      at_start->step();
      work = dem::force_loop_work(at_start->force_pairs(), at_start->particles().size());
    }
    std::set<int> counts(emulate_.begin(), emulate_.end());
    for (const Rounds& m : measured) counts.insert(m.threads);
    const std::vector<int> all(counts.begin(), counts.end());
    // The bytes a step moves, priced against the probed working set that holds the footprint.
    const dem::StepTraffic traffic = dem::step_traffic(count, work.total_pairs());
    std::optional<tn::BandwidthCurve> curve;
    if (memory) {
      curve = memory->curve(traffic.footprint_bytes);
      bandwidth_json = memory->json(traffic.footprint_bytes);
      bandwidth_json["bytes_per_step"] = traffic.bytes;
      fmt::print("\nbandwidth: {}; {:.1f} MB a step in the force pass and the drift\n",
                 memory->describe(traffic.footprint_bytes), traffic.bytes / 1e6);
    }
    const std::vector<dem::EmulatedStep> emulated = dem::emulate_steps(
        work, variant, costs, {1, one, one_step},
        {widest.threads, widest.median_phases(), median(widest.step_s)}, all, curve, traffic);
    const double base = emulated.front().step_s();
    fmt::print("\nemulated (force pass replayed by the force model, calibrated at 1 thread{}):\n",
               curve ? "; force pass and drift at least their bytes over the bandwidth" : "");
    fmt::print("{:>7} {:>12} {:>9} {:>13}\n", "threads", "s/step", "speedup", "Amdahl bound");
    std::map<int, double> by_threads;
    for (const dem::EmulatedStep& e : emulated) {
      by_threads[e.threads] = e.step_s();
      fmt::print("{:>7} {:>12.4g} {:>9.3f} {:>13.3f}\n", e.threads, e.step_s(), base / e.step_s(),
                 amdahl(serial, e.threads));
      nlohmann::json point{{"threads", e.threads},         {"step_s", e.step_s()},
                           {"neighbor_s", e.neighbor_s},   {"force_s", e.force_s},
                           {"integrate_s", e.integrate_s}, {"speedup", base / e.step_s()}};
      if (curve) {
        point["bytes_per_s"] = e.bytes_per_s;
        point["memory_s"] = e.memory_s;
      }
      emulated_json.push_back(point);
    }
    for (const Rounds& m : measured) {
      if (m.threads == 1) continue;
      const double measured_s = median(m.step_s), emulated_s = by_threads[m.threads];
      fmt::print("check at {} threads: measured {:.4g} s/step, emulated {:.4g} ({:+.1f}%)\n",
                 m.threads, measured_s, emulated_s,
                 100.0 * tn::relative_error(emulated_s, measured_s));
      checks.push_back({{"threads", m.threads},
                        {"measured_step_s", measured_s},
                        {"emulated_step_s", emulated_s},
                        {"relative_error", tn::relative_error(emulated_s, measured_s)}});
    }
  }
  if (!json_out_.empty()) {
    std::set<int> bound_counts{2, 8, 16};
    for (const int t : start_.threads) bound_counts.insert(t);
    for (const int t : emulate_) bound_counts.insert(t);
    nlohmann::json bounds = nlohmann::json::array();
    for (const int t : bound_counts)
      bounds.push_back({{"threads", t}, {"bound", amdahl(serial, t)}});
    const nlohmann::json doc{
        {"schema_version", 1},
        {"kind", "contactlab-dem-profile"},
        {"context", tn::collect_context(command_line_, start_.threads.back())},
        {"config", config.name},
        {"particles", count},
        {"variant", dem::to_string(variant)},
        {"step_isa", dem::to_string(dem::step_isa())},
        {"steps", steps},
        {"rounds", rounds_},
        {"phase_split",
         {{"candidates_s", one.neighbor_s},
          {"pair_forces_s", one.pair_forces_s},
          {"reduction_s", one.reduction_s},
          {"wall_forces_s", one.walls_s},
          {"update_s", one.update_s},
          {"integration_s", one.integrate_s}}},
        {"serial_fraction", serial},
        {"serial_fraction_method", serial_method},
        {"amdahl_bound", bounds},
        {"measured", measured_json},
        {"emulated", emulated_json},
        {"bandwidth", bandwidth_json},
        {"validation", checks},
        {"method",
         "Measured: each thread count in interleaved rounds, every round from the same start "
         "(one untimed step, then the timed steps); medians with 95% order-statistic intervals. "
         "Serial fraction: the serial walls and the neighbour list's serial part (serial + "
         "parallel/P fitted to its 1- and widest-measured-thread times; counted whole, an upper "
         "bound, where only one thread was measured), at one thread. Emulated: the force pass "
         "replayed by the force model (libgomp's "
         "schedules over the pair list's blocks) with costs calibrated at one thread and scaled "
         "to the measured one-thread pass; the neighbour list and the integration as serial + "
         "parallel/P fitted from their 1- and widest-measured-thread times; with a machine file "
         "(bandwidth), the force pass and the drift together at least their bytes a step (from the "
         "work counts and the layout) over the bandwidth the thread count draws: the probe's "
         "curve, beyond its threads a saturating law towards the stated ceiling. Not modelled: "
         "shared caches as threads are added, j sides landing in other threads' blocks."}};
    write_json(json_out_, doc);
  }
  return 0;
}

}  // namespace

Subcommand add_dem_profile_command(CLI::App& dem_app, const std::string& command_line) {
  auto profile = std::make_shared<DemProfileCommand>();
  profile->command_line_ = command_line;
  CLI::App* app = dem_app.add_subcommand(
      "profile", "phase split, serial fraction, Amdahl bound against the measured speed-up");
  profile->start_.add_options(app, "thread counts, from 1 (default 1,2)",
                              "timed steps per run (200)");
  app->add_option("--variant", profile->variant_, "force variant (default ordered/static)");
  app->add_option("--emulate", profile->emulate_,
                  "also emulate these thread counts (e.g. 4,8,16; the step replayed by the force "
                  "model, checked at the measured counts)")
      ->delimiter(',');
  profile->memory_.add_to(*app, "--emulate's force pass and drift");
  app->add_option("--rounds", profile->rounds_,
                  "interleaved rounds over the thread counts (medians and 95% intervals; 1)");
  app->add_option("--json", profile->json_out_, "write the profile (docs/emulation.md)");
  return {app, [=] { return profile->run(); }};
}

}  // namespace contactlab::cli
