// `contactlab tune --dem CONFIG`: the DEM force variant for a scene and thread count, by the
// detection tuner's methods: the zero-run model (calibrated by a few runs that isolate its
// costs, then every candidate priced from the pair list alone), a search that times the
// model's three best, and, with --exhaustive, every candidate timed. The choices, the default
// and the report's are then timed in interleaved rounds: regret and the model's error.
#include <fmt/core.h>

#include <algorithm>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cli_shared.hpp"
#include "contactlab/kernels/atomic_file.hpp"
#include "contactlab/kernels/error.hpp"
#include "contactlab/support/statistics.hpp"
#include "contactlab/tuner_dem/force_model.hpp"
#include "contactlab/tuner_dem/variant_study.hpp"
#include "dem_start.hpp"

namespace contactlab::cli {
namespace {

// The search times this many of the model's best.
constexpr std::size_t kSearchWidth = 3;

struct MethodChoice {
  std::string name;
  dem::ForceVariant variant;
  int timed_runs = 0;  // runs of candidates (the model's calibration is counted apart)
};

const dem::VariantStudyRow& fastest(const std::vector<dem::VariantStudyRow>& rows) {
  return *std::min_element(rows.begin(), rows.end(),
                           [](const auto& a, const auto& b) { return a.seconds < b.seconds; });
}

nlohmann::json costs_json(const dem::ForceCosts& c) {
  nlohmann::json per_pair, foreign;
  for (const dem::Accumulation a : {dem::Accumulation::kOrdered, dem::Accumulation::kPerThread,
                                    dem::Accumulation::kAtomic, dem::Accumulation::kFullList}) {
    per_pair[std::string(dem::to_string(a))] = c.per_pair[static_cast<int>(a)];
    foreign[std::string(dem::to_string(a))] = c.per_foreign_j_side[static_cast<int>(a)];
  }
  return {{"threads", c.threads},
          {"runs", c.calibration_runs},
          {"steps_per_run", c.calibration_steps},
          {"spread", c.calibration_spread},
          {"seconds", c.calibration_seconds},
          {"seconds_per_pair", per_pair},
          {"seconds_per_foreign_j_side", foreign},
          {"seconds_per_particle_update", c.per_particle_update},
          {"seconds_per_particle_fused", c.per_particle_fused},
          {"seconds_per_particle_serial_walls", c.per_particle_serial_walls},
          {"seconds_per_particle_arrays", c.per_particle_arrays},
          {"seconds_per_grab", c.per_grab}};
}

}  // namespace

int tune_dem(const DemTuneRequest& request) {
  if (request.steps == 0) throw InputError("--dem-steps must be >= 1");
  if (request.verify_rounds < 1) throw InputError("--verify-rounds must be >= 1");
  if (!request.json_out.empty()) prepare_output_file(request.json_out);
  DemStart start;
  start.config = request.config;
  start.restart = request.restart;
  start.threads = {request.threads};
  start.steps = request.steps;
  const dem::DemConfig config = start.checked_config();
  const dem::Particles particles = dem::make_particles(config);
  const int threads = request.threads;
  const dem::EngineFactory make_engine = [&](const dem::ForceVariant& variant, int t) {
    return start.engine(config, particles, variant, t);
  };
  const std::vector<dem::ForceVariant> candidates = dem::force_variants({1, 4, 16});
  const dem::ForceVariant report_choice =
      dem::parse_force_variant("per-thread/dynamic,1/walls=serial");

  // The model: calibrated on this scene, then every candidate priced with no run.
  const dem::ForceCosts costs = dem::calibrate_force_costs(make_engine, threads, request.steps);
  dem::ForceLoopWork work;
  {
    const std::unique_ptr<dem::Engine> at_start = make_engine(dem::ForceVariant{}, threads);
    at_start->step();
    work = dem::force_loop_work(at_start->force_pairs(), at_start->particles().size());
  }
  const std::vector<dem::RankedVariant> ranked =
      dem::rank_force_variants(work, candidates, threads, costs);
  auto predicted = [&](const dem::ForceVariant& v) {
    return dem::predict_force_pass(work, v, threads, costs).seconds;
  };
  std::vector<MethodChoice> methods{{"model", ranked.front().variant, 0}};
  fmt::print(
      "tune --dem '{}': {} particles, {} pairs, {} threads, {} candidate force variants\n"
      "model: calibrated by {} runs of {} steps ({:.1f} s), then every candidate priced from the "
      "pair list (no run)\n",
      config.name, particles.size(), work.total_pairs(), threads, candidates.size(),
      costs.calibration_runs, costs.calibration_steps, costs.calibration_seconds);

  std::vector<dem::VariantStudyRow> exhaustive_rows;
  if (!request.predict_only) {
    std::vector<dem::ForceVariant> best_predicted;
    for (std::size_t k = 0; k < std::min(kSearchWidth, ranked.size()); ++k) {
      best_predicted.push_back(ranked[k].variant);
    }
    const auto searched = dem::variant_study(make_engine, best_predicted, {threads}, request.steps);
    methods.push_back(
        {"search", fastest(searched).variant, static_cast<int>(best_predicted.size())});
    if (request.exhaustive) {
      exhaustive_rows = dem::variant_study(make_engine, candidates, {threads}, request.steps);
      methods.push_back(
          {"exhaustive", fastest(exhaustive_rows).variant, static_cast<int>(candidates.size())});
    }
  }

  // Verification: the choices, the default and the report's, interleaved rounds.
  std::vector<dem::ForceVariant> verified;
  auto add_verified = [&](const dem::ForceVariant& v) {
    if (std::find(verified.begin(), verified.end(), v) == verified.end()) verified.push_back(v);
  };
  for (const MethodChoice& m : methods) add_verified(m.variant);
  add_verified(dem::ForceVariant{});
  add_verified(report_choice);
  std::map<std::string, std::vector<double>> seconds, force_seconds;
  if (!request.predict_only) {
    for (int round = 0; round < request.verify_rounds; ++round) {
      for (const dem::VariantStudyRow& r :
           dem::variant_study(make_engine, verified, {threads}, request.steps)) {
        seconds[dem::to_string(r.variant)].push_back(r.seconds);
        force_seconds[dem::to_string(r.variant)].push_back(r.force_seconds_per_step);
      }
    }
  }
  auto median_of = [](std::map<std::string, std::vector<double>>& m, const dem::ForceVariant& v) {
    auto& samples = m[dem::to_string(v)];
    return samples.empty() ? 0.0 : median(samples);
  };
  double best_measured = 0.0;
  for (const dem::ForceVariant& v : verified) {
    const double s = median_of(seconds, v);
    if (s > 0 && (best_measured == 0.0 || s < best_measured)) best_measured = s;
  }
  const double step_count = static_cast<double>(request.steps);
  const double particle_count = static_cast<double>(particles.size());

  fmt::print("\n{:<12} {:<44} {:>6} {:>13} {:>13} {:>10} {:>16} {:>8}\n", "", "variant", "runs",
             "pred. ms/step", "meas. ms/step", "model err", "particle-steps/s", "regret");
  nlohmann::json verification = nlohmann::json::array();
  auto print_row = [&](const std::string& label, const dem::ForceVariant& v, int runs) {
    const double pred = predicted(v), meas = median_of(force_seconds, v),
                 total = median_of(seconds, v);
    const bool timed = total > 0;
    fmt::print("{:<12} {:<44} {:>6} {:>13.4f} {:>13} {:>10} {:>16} {:>8}\n", label,
               dem::to_string(v), runs >= 0 ? std::to_string(runs) : std::string("-"), 1e3 * pred,
               timed ? fmt::format("{:.4f}", 1e3 * meas) : "-",
               timed ? fmt::format("{:+.1f}%", 100.0 * (pred / meas - 1.0)) : "-",
               timed ? fmt::format("{:.4g}", particle_count * step_count / total) : "-",
               timed ? fmt::format("{:+.1f}%", 100.0 * (total / best_measured - 1.0)) : "-");
    nlohmann::json row{{"label", label},
                       {"variant", dem::to_string(v)},
                       {"predicted_force_seconds_per_step", pred}};
    if (runs >= 0) row["timed_runs"] = runs;
    if (timed) {
      row["measured_force_seconds_per_step"] = meas;
      row["model_error"] = pred / meas - 1.0;
      row["particle_steps_per_s"] = particle_count * step_count / total;
      row["regret"] = total / best_measured - 1.0;
    }
    verification.push_back(row);
  };
  for (const MethodChoice& m : methods) print_row(m.name, m.variant, m.timed_runs);
  print_row("default", dem::ForceVariant{}, -1);
  print_row("report's", report_choice, -1);
  // The choice: the method's whose variant ran fastest in the verification (the model's when
  // nothing was timed).
  const MethodChoice* chosen_by = &methods.front();
  for (const MethodChoice& m : methods) {
    const double s = median_of(seconds, m.variant);
    if (s > 0 && s < median_of(seconds, chosen_by->variant)) chosen_by = &m;
  }
  const dem::ForceVariant chosen = chosen_by->variant;
  fmt::print(
      "\nchosen      {} (by {}){}\n"
      "pred./meas. ms/step: the force pass (pairs, reduction, walls, update) per step, "
      "predicted by the model and measured (median of {} interleaved rounds); "
      "particle-steps/s and regret: whole steps\n",
      dem::to_string(chosen), chosen_by->name,
      request.predict_only ? " (predicted only: nothing timed)" : "", request.verify_rounds);

  if (!request.json_out.empty()) {
    nlohmann::json doc;
    doc["kind"] = "dem_force_variant_tuning";
    doc["config"] = request.config;
    doc["threads"] = threads;
    doc["steps"] = request.steps;
    doc["verify_rounds"] = request.predict_only ? 0 : request.verify_rounds;
    doc["chosen"] = dem::to_string(chosen);
    doc["calibration"] = costs_json(costs);
    doc["methods"] = nlohmann::json::array();
    for (const MethodChoice& m : methods) {
      doc["methods"].push_back(
          {{"name", m.name}, {"choice", dem::to_string(m.variant)}, {"timed_runs", m.timed_runs}});
    }
    doc["verification"] = verification;
    doc["predictions"] = nlohmann::json::array();
    for (const dem::RankedVariant& r : ranked) {
      doc["predictions"].push_back({{"variant", dem::to_string(r.variant)},
                                    {"force_seconds_per_step", r.prediction.seconds},
                                    {"pass_s", r.prediction.pass_seconds},
                                    {"reduction_s", r.prediction.reduction_seconds},
                                    {"walls_s", r.prediction.walls_seconds},
                                    {"update_s", r.prediction.update_seconds}});
    }
    doc["exhaustive"] = nlohmann::json::array();
    for (const dem::VariantStudyRow& r : exhaustive_rows) {
      doc["exhaustive"].push_back({{"variant", dem::to_string(r.variant)},
                                   {"seconds", r.seconds},
                                   {"force_seconds_per_step", r.force_seconds_per_step},
                                   {"particle_steps_per_s", r.particle_steps_per_s},
                                   {"max_deviation_diameters", r.max_deviation},
                                   {"bit_identical_to_default", r.bit_identical}});
    }
    write_file_atomically(request.json_out, [&](std::ostream& out) { out << doc.dump(2) << '\n'; });
  }
  return 0;
}

}  // namespace contactlab::cli
