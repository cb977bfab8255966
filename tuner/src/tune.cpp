#include "contactlab/tuner/tune.hpp"

#include <fmt/core.h>
#include <omp.h>

#include <algorithm>
#include <array>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <random>
#include <utility>

#include "contactlab/kernels/atomic_file.hpp"
#include "contactlab/kernels/detector.hpp"
#include "contactlab/kernels/error.hpp"
#include "contactlab/kernels/scene_generate.hpp"
#include "contactlab/tuner/chunk_formulas.hpp"
#include "contactlab/tuner/chunk_search.hpp"
#include "contactlab/tuner/context.hpp"
#include "contactlab/tuner/cost_calibration.hpp"
#include "contactlab/tuner/statistics.hpp"
#include "contactlab/tuner/sweep.hpp"

namespace contactlab::tuner {
namespace {

using nlohmann::json;

const Variant kReference = parse_variant("particle/sorted/half/static");
// Timed runs per calibration point; their median is fitted (a single run on a shared VM can
// take twice as long when a vCPU is stolen).
constexpr int kCalibrationSamples = 5;

WorkView view_of(const LoopWork& work) { return {work.tests, work.homes, work.builds}; }

// Every loop/order/stencil/precision the options allow, with a placeholder schedule.
std::vector<Variant> structures_of(const TuneOptions& options) {
  return enumerate(VariantSpace{
      options.loops, options.orders, options.stencils, {Schedule{}}, options.precisions});
}

Variant with_schedule(Variant v, ScheduleKind kind, int chunk) {
  v.schedule = Schedule{kind, chunk};
  return v;
}

// T_c samples of `count` timed runs (after the detector's buffers are warm).
std::vector<double> detect_samples(ContactDetector& detector, const Scene& scene,
                                   const DetectOptions& options, int count) {
  std::vector<double> samples;
  for (int i = 0; i < count; ++i) samples.push_back(detector.run(scene, options).detect_s);
  return samples;
}

json summary_json(const std::vector<double>& samples) {
  const Summary s = summarize(samples);
  return {{"median_s", s.median},
          {"ci95_low_s", s.interval.low},
          {"ci95_high_s", s.interval.high},
          {"samples_s", samples}};
}

// The model's best schedule for one structure: every kind, every chunk of the grid.
struct ModelChoice {
  Variant variant;
  double predicted_s = 0.0;
  std::vector<CandidatePrediction> candidates;  // of the chosen kind
};

ModelChoice model_choice(const Variant& structure, WorkView work, int threads,
                         const MachineCosts& costs, const std::vector<int>& grid) {
  ModelChoice best;
  best.predicted_s = std::numeric_limits<double>::infinity();
  const PreparedWork prepared(work);
  for (const auto kind : {ScheduleKind::kStatic, ScheduleKind::kDynamic, ScheduleKind::kGuided}) {
    std::vector<int> candidates = grid;
    if (kind == ScheduleKind::kStatic) candidates.insert(candidates.begin(), 0);  // block
    const ChunkPrediction p = predict_best_chunk(prepared, threads, kind, costs, candidates);
    if (p.best_seconds < best.predicted_s) {
      best = {with_schedule(structure, kind, p.best_chunk), p.best_seconds, p.candidates};
    }
  }
  return best;
}

// The final verification's timings: `rounds` samples of every distinct variant among the
// contenders, taken round by round in a new random order each round (fixed seed).
struct Verification {
  std::vector<Variant> distinct;
  std::vector<std::size_t> of_contender;     // contender -> index into distinct
  std::vector<std::vector<double>> samples;  // per distinct variant, one per round
  std::size_t best = 0;                      // distinct variant with the fastest paired ratio

  const std::vector<double>& samples_of(std::size_t contender) const {
    return samples[of_contender[contender]];
  }
  const std::vector<double>& best_samples() const { return samples[best]; }
};

Verification verify_choices(ContactDetector& detector, const Scene& scene, double diameter,
                            int threads,
                            const std::vector<std::pair<std::string, Variant>>& contenders,
                            int rounds) {
  Verification v;
  for (const auto& [name, variant] : contenders) {
    const auto found = std::find(v.distinct.begin(), v.distinct.end(), variant);
    v.of_contender.push_back(static_cast<std::size_t>(found - v.distinct.begin()));
    if (found == v.distinct.end()) v.distinct.push_back(variant);
  }
  v.samples.resize(v.distinct.size());
  std::vector<std::size_t> order(v.distinct.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::mt19937_64 random(20131001);
  for (const Variant& variant : v.distinct)
    detector.run(scene, DetectOptions{variant, diameter, threads, nullptr});  // warm-up
  for (int round = 0; round < rounds; ++round) {
    std::shuffle(order.begin(), order.end(), random);
    for (const std::size_t i : order) {
      v.samples[i].push_back(
          detector.run(scene, DetectOptions{v.distinct[i], diameter, threads, nullptr}).detect_s);
    }
  }
  // The fastest: the smallest median of paired ratios against the first contender (any fixed
  // reference ranks the same way up to noise, and this one is always present).
  double best_ratio = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < v.distinct.size(); ++i) {
    const double r = paired_ratio(v.samples[i], v.samples[0]).median;
    if (r < best_ratio) {
      best_ratio = r;
      v.best = i;
    }
  }
  return v;
}

}  // namespace

std::string structure_key(const Variant& variant) {
  std::string key = std::string(to_string(variant.loop)) + "/" +
                    std::string(to_string(variant.order)) + "/" +
                    std::string(to_string(variant.stencil));
  if (variant.precision != Precision::kDouble)
    key += "/" + std::string(to_string(variant.precision));
  return key;
}

Calibration calibrate_machine(const TuneOptions& options, int threads) {
  const double start = omp_get_wtime();
  // Two sizes of one dense clustered scene, timed under schedules that exercise every cost
  // term, separate time per pair test from the fixed costs. A sparse uniform scene (about 0.1
  // particles per cell, few tests per particle) identifies the costs of homes and of
  // neighbour-range builds in a grid larger than the caches, which dominate sparse scenes and
  // which dense scenes alone leave free; block, block-cyclic and dynamic suffice there. Each
  // is small enough to calibrate in seconds.
  const std::vector<Schedule> every_term{{ScheduleKind::kStatic, 0},  {ScheduleKind::kStatic, 1},
                                         {ScheduleKind::kStatic, 64}, {ScheduleKind::kStatic, 4096},
                                         {ScheduleKind::kDynamic, 1}, {ScheduleKind::kDynamic, 64},
                                         {ScheduleKind::kGuided, 64}};
  const std::vector<Schedule> sparse_terms{
      {ScheduleKind::kStatic, 0}, {ScheduleKind::kStatic, 64}, {ScheduleKind::kDynamic, 64}};
  struct CalibrationScene {
    Scene scene;
    double diameter;
    const std::vector<Schedule>& schedules;
  };
  std::vector<CalibrationScene> scenes;
  auto add_scene = [&](SceneKind kind, std::uint64_t n, double diameter,
                       const std::vector<Schedule>& schedules) {
    SceneSpec spec;
    spec.kind = kind;
    spec.n = n;
    spec.diameter = diameter;
    scenes.push_back({generate_scene(spec), diameter, schedules});
  };
  add_scene(SceneKind::kClustered, 40'000, 1.0 / 100.0, every_term);
  add_scene(SceneKind::kClustered, 120'000, 1.0 / 100.0, every_term);
  add_scene(SceneKind::kUniform, 300'000, 1.0 / 150.0, sparse_terms);
  ContactDetector detector;
  Calibration calibration;
  calibration.source = "calibrated now";
  calibration.threads = threads;
  std::vector<int> thread_counts{1};
  if (threads > 1) thread_counts.push_back(threads);
  for (const Variant& structure : structures_of(options)) {
    std::vector<LoopWork> works;  // kept alive: TimedRun holds views
    for (const CalibrationScene& c : scenes) {
      works.push_back(
          detector.iteration_work(c.scene, DetectOptions{structure, c.diameter, 1, nullptr}));
    }
    std::vector<TimedRun> runs;
    for (std::size_t s = 0; s < scenes.size(); ++s) {
      for (const int t : thread_counts) {
        for (const Schedule& schedule : scenes[s].schedules) {
          Variant v = structure;
          v.schedule = schedule;
          const DetectOptions options_now{v, scenes[s].diameter, t, nullptr};
          detector.run(scenes[s].scene, options_now);  // warm-up
          runs.push_back({view_of(works[s]), t, schedule,
                          median(detect_samples(detector, scenes[s].scene, options_now,
                                                kCalibrationSamples))});
        }
      }
    }
    const CalibrationResult fit = calibrate_costs(runs);
    calibration.structures[structure_key(structure)] = {fit.costs, fit.rms_relative_error,
                                                        static_cast<int>(runs.size())};
  }
  calibration.seconds = omp_get_wtime() - start;
  return calibration;
}

TuneReport tune(const Scene& scene, const SceneRecord& scene_record, double diameter,
                const TuneOptions& options, const Calibration& calibration,
                const std::string& command_line) {
  const int threads = resolve_threads(options.threads);
  if (options.chunk_grid.empty()) throw InputError("tune: the chunk grid is empty");
  if (options.search_samples < 1 || options.exhaustive_rounds < 1 || options.verify_rounds < 1) {
    throw InputError(fmt::format(
        "tune: search samples ({}), exhaustive rounds ({}) and verification rounds ({}) must be "
        ">= 1",
        options.search_samples, options.exhaustive_rounds, options.verify_rounds));
  }
  ContactDetector detector;
  json report;
  report["schema_version"] = kTuneSchemaVersion;
  Context context = collect_context(command_line, threads);
  report["context"] = context;
  report["scene"] = scene_record;
  report["diameter"] = scene.has_diameters() ? json(nullptr) : json(diameter);
  report["threads"] = threads;
  report["chunk_grid"] = options.chunk_grid;
  report["calibration"] = {{"source", calibration.source}, {"seconds", calibration.seconds}};

  // Model: zero timed runs on this scene. Its cost is the work profiles (registration and a
  // pass over the stencils per structure).
  const double model_start = omp_get_wtime();
  struct Structure {
    Variant variant;
    LoopWork work;
    MachineCosts costs;
    ModelChoice model;
  };
  std::vector<Structure> structures;
  json model_table = json::array();
  for (const Variant& structure : structures_of(options)) {
    const auto found = calibration.structures.find(structure_key(structure));
    const MachineCosts costs =
        found != calibration.structures.end() ? found->second.costs : MachineCosts{};
    Structure s{
        structure,
        detector.iteration_work(scene, DetectOptions{structure, diameter, threads, nullptr}),
        costs,
        {}};
    s.model = model_choice(structure, view_of(s.work), threads, costs, options.chunk_grid);
    model_table.push_back(
        {{"variant", to_string(s.model.variant)}, {"predicted_s", s.model.predicted_s}});
    structures.push_back(std::move(s));
  }
  // Without a tolerance the model cannot vouch for single precision: it never runs.
  const Structure* model_best = nullptr;
  for (const Structure& s : structures) {
    if (s.variant.precision != Precision::kDouble && options.tolerance == 0) continue;
    if (!model_best || s.model.predicted_s < model_best->model.predicted_s) model_best = &s;
  }
  if (!model_best) throw InputError("tune: no structure left to choose from");
  const double model_cost = omp_get_wtime() - model_start;
  json methods = json::array();
  json model_method = {{"method", "model"},
                       {"variant", to_string(model_best->model.variant)},
                       {"chunk", model_best->model.variant.schedule.chunk},
                       {"predicted_s", model_best->model.predicted_s},
                       {"timed_runs", 0},
                       {"tuning_cost_s", model_cost},
                       {"structures", model_table}};

  // Other thread counts, from the model's structure.
  json predictions = json::array();
  for (const int p : options.predict_threads) {
    const ModelChoice m = model_choice(model_best->variant, view_of(model_best->work), p,
                                       model_best->costs, options.chunk_grid);
    predictions.push_back(
        {{"threads", p},
         {"variant", to_string(m.variant)},
         {"predicted_s", m.predicted_s},
         {"label", p > omp_get_num_procs()
                       ? "predicted (model only: more threads than this machine has)"
                       : "predicted (model only)"}});
  }
  report["predictions"] = predictions;
  // Classic formulas for the structure that is tuned (the model's here, the search's below).
  auto classic_report = [&](const Structure& structure) {
    json classic = json::array();
    for (const NamedChunk& c : classic_chunks(view_of(structure.work), threads, structure.costs)) {
      classic.push_back({{"name", c.name},
                         {"chunk", c.chunk},
                         {"inputs", c.inputs},
                         {"structure", structure_key(structure.variant)}});
    }
    return classic;
  };
  report["classic"] = classic_report(*model_best);

  TuneReport result;
  result.chosen = model_best->model.variant;
  if (options.predict_only) {
    methods.push_back(model_method);
    report["methods"] = methods;
    result.json = std::move(report);
    return result;
  }

  // Search, step 1: screen every structure at its modelled schedule; single precision is
  // checked against the exact contacts and dropped when wrong beyond the tolerance.
  const double search_start = omp_get_wtime();
  detector.run(scene, DetectOptions{kReference, diameter, threads, nullptr});
  const ContactList reference = detector.canonical_contacts();
  json screening = json::array();
  const Structure* screened_best = nullptr;
  double screened_best_s = std::numeric_limits<double>::infinity();
  for (const Structure& s : structures) {
    const DetectOptions o{s.model.variant, diameter, threads, nullptr};
    detector.run(scene, o);
    const std::vector<double> samples = detect_samples(detector, scene, o, options.search_samples);
    const auto [missing, extra] = contact_differences(reference, detector.canonical_contacts());
    const bool acceptable = missing + extra <= options.tolerance;
    const double m = median(samples);
    screening.push_back({{"variant", to_string(s.model.variant)},
                         {"median_s", m},
                         {"wrong_contacts", {{"missing", missing}, {"extra", extra}}},
                         {"acceptable", acceptable}});
    if (acceptable && m < screened_best_s) {
      screened_best_s = m;
      screened_best = &s;
    }
  }
  if (!screened_best)
    throw InputError("tune: every structure had wrong contacts beyond the tolerance");
  const double screening_cost = omp_get_wtime() - search_start;

  // Step 2: noise-aware search over k for the best structure and its modelled schedule kind.
  const ScheduleKind kind = screened_best->model.variant.schedule.kind;
  auto measure_chunk = [&](int chunk) {
    const DetectOptions o{with_schedule(screened_best->variant, kind, chunk), diameter, threads,
                          nullptr};
    return detect_samples(detector, scene, o, options.search_samples);
  };
  ChunkSearchOptions search_options;
  search_options.grid = options.chunk_grid;
  const int model_chunk = screened_best->model.variant.schedule.chunk;
  search_options.seed_chunk = model_chunk > 0 ? model_chunk : options.chunk_grid.back();
  // Budget: a fifth of what the exhaustive sweep would spend, in measured runs.
  // What the bracket and golden section leave of the budget goes to confirming the chunks
  // still equivalent to the fastest (more samples, narrower intervals).
  search_options.confirmation_rounds = 2;
  search_options.budget.max_evaluations =
      std::max(3, static_cast<int>(options.chunk_grid.size()) * options.exhaustive_rounds / 5 /
                      options.search_samples);
  const ChunkSearchResult searched = search_chunk(measure_chunk, search_options);
  const Variant search_variant = with_schedule(screened_best->variant, kind, searched.chosen_chunk);
  // The search stands on the model (its seed and its schedule kind): its cost includes it.
  const double search_cost = omp_get_wtime() - search_start + model_cost;
  result.chosen = search_variant;
  json search_method = {
      {"method", "search"},
      {"variant", to_string(search_variant)},
      {"chunk", searched.chosen_chunk},
      {"timed_runs", searched.evaluations * options.search_samples +
                         static_cast<int>(structures.size()) * (1 + options.search_samples)},
      {"chunk_search_timed_runs", searched.evaluations * options.search_samples},
      {"evaluations", searched.evaluations},
      {"screening_cost_s", screening_cost},
      {"model_cost_s", model_cost},
      {"chunk_search_cost_s", search_cost - screening_cost - model_cost},
      {"tuning_cost_s", search_cost},
      {"screening", screening}};
  json searched_points = json::array();
  for (const ChunkMeasurement& m : searched.measured) {
    searched_points.push_back({{"chunk", m.chunk}, {"median_s", m.median_seconds}});
  }
  search_method["chunks_measured"] = searched_points;

  report["classic"] = classic_report(*screened_best);

  // Exhaustive: every chunk for the searched structure and kind, in interleaved rounds. Its
  // fastest chunk is the exhaustive best.
  std::optional<Variant> exhaustive_variant;
  if (options.exhaustive) {
    const double exhaustive_start = omp_get_wtime();
    auto measure_exhaustive = [&](int chunk) {
      const DetectOptions o{with_schedule(screened_best->variant, kind, chunk), diameter, threads,
                            nullptr};
      return detect_samples(detector, scene, o, 1);
    };
    ChunkSearchOptions exhaustive_options = search_options;
    exhaustive_options.rounds = options.exhaustive_rounds;
    const ChunkSearchResult all = exhaustive_chunk_sweep(measure_exhaustive, exhaustive_options);
    json points = json::array();
    for (const ChunkMeasurement& m : all.measured) {
      points.push_back({{"chunk", m.chunk},
                        {"median_s", m.median_seconds},
                        {"ci95_low_s", m.interval.low},
                        {"ci95_high_s", m.interval.high}});
    }
    exhaustive_variant = with_schedule(screened_best->variant, kind, all.fastest_chunk);
    methods.push_back({{"method", "exhaustive"},
                       {"variant", to_string(*exhaustive_variant)},
                       {"chunk", all.fastest_chunk},
                       {"largest_equivalent_chunk", all.chosen_chunk},
                       {"rounds", options.exhaustive_rounds},
                       {"timed_runs", all.evaluations},
                       {"tuning_cost_s", omp_get_wtime() - exhaustive_start},
                       {"chunks_measured", points}});
  }

  // Verification: each method's choice and each classic formula's k timed alike, every
  // distinct variant once per round in a new random order. Comparisons are paired ratios
  // within rounds (drift of the machine cancels), and regret is against the fastest verified
  // choice, not the minimum of the exhaustive sweep's own medians (biased low by noise).
  std::vector<std::pair<std::string, Variant>> contenders{{"model", model_best->model.variant},
                                                          {"search", search_variant}};
  if (exhaustive_variant) contenders.push_back({"exhaustive", *exhaustive_variant});
  const std::size_t first_classic = contenders.size();
  for (const auto& c : report["classic"]) {
    contenders.push_back(
        {"classic", with_schedule(screened_best->variant, kind, c["chunk"].get<int>())});
  }
  const Verification verified =
      verify_choices(detector, scene, diameter, threads, contenders, options.verify_rounds);
  auto attach = [&](json& target, std::size_t index) {
    target["measured"] = summary_json(verified.samples_of(index));
    const PairedRatio to_best = paired_ratio(verified.samples_of(index), verified.best_samples());
    target["regret"] = to_best.median - 1.0;
    target["regret_ci95"] = {to_best.interval.low - 1.0, to_best.interval.high - 1.0};
    if (exhaustive_variant) {
      const PairedRatio to_exhaustive =
          paired_ratio(verified.samples_of(index), verified.samples_of(2));
      target["vs_exhaustive"] = {
          {"ratio_minus_one", to_exhaustive.median - 1.0},
          {"ci95", {to_exhaustive.interval.low - 1.0, to_exhaustive.interval.high - 1.0}}};
    }
  };
  report["verification"] = {
      {"rounds", options.verify_rounds},
      {"distinct_variants", verified.distinct.size()},
      {"best", to_string(verified.distinct[verified.best])},
      {"regret_against", "fastest verified choice; median of per-round paired ratios - 1"}};
  attach(model_method, 0);
  attach(search_method, 1);
  if (exhaustive_variant) attach(methods.back(), 2);
  methods.insert(methods.begin(), search_method);
  methods.insert(methods.begin(), model_method);
  for (std::size_t c = first_classic; c < contenders.size(); ++c) {
    json& entry = report["classic"][c - first_classic];
    entry["variant"] = to_string(contenders[c].second);
    attach(entry, c);
  }
  report["methods"] = methods;
  result.json = std::move(report);
  return result;
}

}  // namespace contactlab::tuner
