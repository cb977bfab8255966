// contactlab: the command-line program. Parses options, calls the libraries, prints.
#include <fmt/core.h>
#include <omp.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <optional>

#include "contactlab/kernels/atomic_file.hpp"
#include "contactlab/kernels/detector.hpp"
#include "contactlab/kernels/error.hpp"
#include "contactlab/kernels/scene_generate.hpp"
#include "contactlab/kernels/scene_io.hpp"
#include "contactlab/tuner/cache_sim.hpp"
#include "contactlab/tuner/context.hpp"
#include "contactlab/tuner/measure.hpp"
#include "contactlab/tuner/papi_counters.hpp"
#include "contactlab/tuner/result_schema.hpp"
#include "contactlab/tuner/sweep.hpp"
#include "contactlab/tuner/tune.hpp"

namespace cl = contactlab;
namespace tn = contactlab::tuner;

namespace {

// Where the particles come from: a file, or a generator spec.
struct SceneOptions {
  std::string input;
  std::string kind = "clustered";
  std::uint64_t n = 100'000;
  double diameter = 0.0;
  bool diameter_given = false;
  std::uint64_t seed = 1;
  std::string box;
  double core = cl::SceneSpec{}.core;
  double background = cl::SceneSpec{}.background;
  int blobs = cl::SceneSpec{}.blob_count;
  double size_ratio = cl::SceneSpec{}.size_ratio;

  void add_to(CLI::App& app, bool with_input) {
    if (with_input) app.add_option("--input", input, "particle file (text x,y,z[,d] or binary)");
    app.add_option(with_input ? "--scene" : "--kind", kind,
                   "generated scene: uniform, clustered, blobs, polydisperse");
    app.add_option("--n", n, "number of particles of a generated scene");
    app.add_option("--diameter,-D", diameter, "particle diameter D (contact distance)")
        ->each([this](const std::string&) { diameter_given = true; });
    app.add_option("--seed", seed, "generator seed");
    app.add_option("--box", box, "box xmin,ymin,zmin,xmax,ymax,zmax (default unit cube)");
    app.add_option("--core", core, "clustered/blobs: relative core radius c (docs/scenes.md)");
    app.add_option("--background", background, "clustered/blobs: fraction spread uniformly");
    app.add_option("--blobs", blobs, "blobs: number of clusters");
    app.add_option("--size-ratio", size_ratio, "polydisperse: largest / smallest diameter");
  }

  cl::SceneSpec spec() const {
    cl::SceneSpec s;
    s.kind = cl::parse_scene_kind(kind);
    s.n = n;
    s.diameter = diameter;
    s.seed = seed;
    if (!box.empty()) s.box = cl::parse_box(box);
    s.core = core;
    s.background = background;
    s.blob_count = blobs;
    s.size_ratio = size_ratio;
    return s;
  }

  void require_diameter() const {
    if (!diameter_given) throw cl::InputError("--diameter is required");
    if (!(diameter > 0.0) || !std::isfinite(diameter)) {
      throw cl::InputError(
          fmt::format("--diameter must be a positive finite number, got {}", diameter));
    }
  }

  // The scene and its description for result files.
  std::pair<cl::Scene, tn::SceneRecord> load() const {
    if (!input.empty()) {
      const cl::Box b = box.empty() ? cl::Box{} : cl::parse_box(box);
      cl::Scene scene = cl::read_scene(input, b);
      if (!scene.has_diameters()) require_diameter();
      tn::SceneRecord record = tn::describe_file_scene(input, scene, diameter);
      return {std::move(scene), std::move(record)};
    }
    require_diameter();
    const cl::SceneSpec s = spec();
    cl::Scene scene = cl::generate_scene(s);
    tn::SceneRecord record = tn::describe_generated_scene(s, scene);
    return {std::move(scene), std::move(record)};
  }
};

int command_scene(const SceneOptions& options, const std::string& out) {
  options.require_diameter();
  cl::check_writable(out);
  const cl::Scene scene = cl::generate_scene(options.spec());
  const bool text = out.ends_with(".csv") || out.ends_with(".txt");
  if (text) {
    cl::write_text_scene(scene, out);
  } else {
    cl::write_binary_scene(scene, out);
  }
  fmt::print("wrote {} particles ({}) to {}, checksum {:016x}\n", scene.size(),
             text ? "text" : "binary", out, cl::scene_checksum(scene));
  return 0;
}

struct DetectCommand {
  std::string variant = "particle/sorted/full/static,200";
  int threads = 0;
  int repeat = 3;
  int warmup = 1;
  bool adaptive = false;
  double target_ci = 0.02;
  double time_budget = 60.0;
  int max_repeat = 200;
  bool papi = false;
  std::string papi_events;
  std::string cache_sim;
  std::string cache_file;  // tuning cache for --variant auto
  std::string contacts_out;
  std::string json_out;
};

std::vector<std::string> split_list(const std::string& text) {
  std::vector<std::string> items;
  std::size_t pos = 0;
  while (pos <= text.size()) {
    const auto comma = text.find(',', pos);
    std::string item =
        text.substr(pos, comma == std::string::npos ? std::string::npos : comma - pos);
    if (item.empty()) throw cl::InputError("--papi-events: empty event name in '" + text + "'");
    items.push_back(std::move(item));
    if (comma == std::string::npos) break;
    pos = comma + 1;
  }
  return items;
}

std::string percent(const std::optional<double>& value) {
  return value ? fmt::format("{:.3f}%", *value) : std::string("n/a");
}

void print_counters(const tn::CounterRecord& c) {
  if (!c.available) {
    fmt::print("counters {}: unavailable: {}\n", c.source, c.reason);
    return;
  }
  fmt::print("counters {}: L1 miss {}  L2 miss {}{}\n", c.source, percent(c.l1_miss_percent),
             percent(c.l2_miss_percent), c.simulation ? "  (simulated; an approximation)" : "");
  for (const auto& e : c.events) {
    std::string threads;
    for (const auto v : e.per_thread) threads += (threads.empty() ? "" : ", ") + std::to_string(v);
    fmt::print("  {:<28} {:>16}{}\n", e.name, e.total,
               threads.empty() ? "" : "  per thread [" + threads + "]");
  }
}

tn::Calibration machine_calibration(tn::TuningCache& cache, const tn::TuneOptions& options,
                                    int threads, bool recalibrate) {
  if (!recalibrate) {
    if (auto cached = cache.calibration()) return *cached;
  }
  fmt::print(stderr,
             "contactlab: calibrating the cost model on this machine (once; cached in {})...\n",
             cache.path());
  tn::Calibration calibration = tn::calibrate_machine(options, threads);
  cache.store_calibration(calibration);
  return calibration;
}

// `--variant auto`: the tuning cache's choice for this machine, build, scene and thread count;
// on a miss the tuner's search chooses, and the choice is cached.
cl::Variant auto_variant(const cl::Scene& scene, const tn::SceneRecord& record, double diameter,
                         int threads, const std::string& cache_file,
                         const std::string& command_line) {
  tn::TuningCache cache(cache_file.empty() ? tn::TuningCache::default_path() : cache_file);
  if (auto cached = cache.choice(record, diameter, threads)) {
    fmt::print(stderr, "contactlab: --variant auto: {} (from {})\n", cl::to_string(*cached),
               cache.path());
    return *cached;
  }
  tn::TuneOptions options;
  options.threads = threads;
  const tn::Calibration calibration = machine_calibration(cache, options, threads, false);
  fmt::print(stderr, "contactlab: --variant auto: no cached choice, tuning...\n");
  const tn::TuneReport report =
      tn::tune(scene, record, diameter, options, calibration, command_line);
  cache.store_choice(record, diameter, threads, report.chosen, 0.0);
  fmt::print(stderr, "contactlab: --variant auto: {} (stored in {})\n",
             cl::to_string(report.chosen), cache.path());
  return report.chosen;
}

int command_detect(const SceneOptions& scene_options, const DetectCommand& command,
                   const std::string& command_line) {
  if (command.repeat < 1) throw cl::InputError("--repeat must be >= 1");
  if (command.warmup < 0) throw cl::InputError("--warmup must be >= 0");
  if (command.threads < 0) throw cl::InputError("--threads must be >= 0");
  if (command.adaptive) {
    if (!(command.target_ci > 0.0 && command.target_ci < 1.0)) {
      throw cl::InputError(fmt::format(
          "--target-ci must be in (0, 1) (a fraction: 0.02 = 2%), got {}", command.target_ci));
    }
    if (!(command.time_budget > 0.0)) throw cl::InputError("--time-budget must be > 0 seconds");
    if (command.max_repeat < command.repeat)
      throw cl::InputError("--max-repeat must be >= --repeat");
  }
  const bool automatic = command.variant == "auto";
  const int threads = cl::resolve_threads(command.threads);
  if (automatic && !command.cache_sim.empty()) {
    throw cl::InputError("--cache-sim needs an explicit --variant (not auto)");
  }

  std::optional<tn::CacheGeometry> geometry;
  if (!command.cache_sim.empty()) geometry = tn::parse_cache_geometry(command.cache_sim);
  if (!command.contacts_out.empty()) cl::check_writable(command.contacts_out);
  if (!command.json_out.empty()) cl::check_writable(command.json_out);
  std::optional<tn::PapiCounters> papi;
  if (command.papi || !command.papi_events.empty()) {
    papi.emplace(command.papi_events.empty() ? std::vector<std::string>{}
                                             : split_list(command.papi_events));
  }
  auto [scene, scene_record] = scene_options.load();
  const cl::Variant variant = automatic ? auto_variant(scene, scene_record, scene_options.diameter,
                                                       threads, command.cache_file, command_line)
                                        : cl::parse_variant(command.variant);

  tn::ResultFile result;
  result.context = tn::collect_context(command_line, threads);
  for (const auto& w : result.context.warnings) fmt::print(stderr, "contactlab: warning: {}\n", w);

  cl::DetectOptions options{variant, scene_options.diameter, threads, nullptr};
  tn::MeasureOptions measure;
  measure.repetition = {command.warmup,
                        command.repeat,
                        command.adaptive,
                        command.target_ci,
                        command.time_budget,
                        command.max_repeat,
                        0.95};
  measure.papi = papi ? &*papi : nullptr;
  cl::ContactDetector detector;
  tn::RunRecord run = tn::measure_detection(detector, scene, scene_record, options, measure);

  if (geometry) {
    fmt::print(stderr, "contactlab: simulating the {} caches under valgrind (slow)...\n",
               geometry->name);
    run.counters.push_back(
        tn::simulate_detection_caches(scene, scene_options.diameter, variant, threads, *geometry));
  }

  const tn::RunAggregates& a = *run.aggregates;
  const tn::RunWork& w = *run.work;
  fmt::print("variant {}  threads {}  N {}  grid {}x{}x{}  max occupancy {}\n",
             run.parameters.variant, run.parameters.threads, scene.size(), w.grid[0], w.grid[1],
             w.grid[2], w.max_cell_occupancy);
  auto line = [](const char* name, const tn::Summary& s) {
    const std::string interval =
        s.count < 2 ? std::string("no interval from 1 sample")
                    : fmt::format("[{:.6f}, {:.6f}] covers the median with {:.1f}%", s.interval.low,
                                  s.interval.high, 100.0 * s.interval.coverage);
    fmt::print("{:<6} median {:.6f} s  {}  min {:.6f}  max {:.6f}\n", name, s.median, interval,
               s.min, s.max);
  };
  fmt::print("{} repetitions after {} warm-up ({}), T_ALL = T_s + T_c:\n", a.repetitions,
             a.warmup_runs, tn::to_string(a.stop_reason));
  line("T_s", a.setup_s);
  line("T_c", a.detect_s);
  line("T_ALL", a.total_s);
  fmt::print("load imbalance (t_max - t_mean) / t_max: median {:.3f}\n", a.imbalance.median);
  fmt::print("candidate tests {}  contacts {}\n", w.candidate_tests, w.contact_pairs);
  for (const auto& c : run.counters) {
    print_counters(c);
    if (!c.available)
      fmt::print(stderr,
                 "contactlab: warning: no {} counters (reason above and in the result file)\n",
                 c.source);
  }
  if (run.status != tn::RunStatus::kOk)
    fmt::print(stderr, "contactlab: run {}: {}\n", tn::to_string(run.status), run.message);

  if (!command.contacts_out.empty())
    cl::write_pairs_csv(detector.canonical_contacts(), command.contacts_out);
  const bool ok = run.status == tn::RunStatus::kOk;
  result.runs.push_back(std::move(run));
  if (!command.json_out.empty()) tn::write_result_file(command.json_out, result);
  return ok ? 0 : 1;
}

int command_sweep(const std::string& config, const tn::SweepOptions& options) {
  const tn::Experiment experiment = tn::read_experiment(config);
  const tn::SweepSummary summary = tn::run_sweep(experiment, options);
  fmt::print("{}: {} points, {} already done, {} ok, {} invalid, {} failed, {:.1f} s -> {}\n",
             experiment.name, summary.points, summary.skipped, summary.ok, summary.invalid,
             summary.failed, summary.seconds, options.out);
  return summary.failed || summary.invalid ? 1 : 0;
}

struct TuneCommand {
  int threads = 0;
  std::string json_out;
  std::string cache_file;
  bool predict_only = false;
  bool exhaustive = false;
  bool recalibrate = false;
  std::uint64_t tolerance = 0;
  int max_chunk = 65536;
  std::string orders = "sorted,morton";
  int search_samples = tn::TuneOptions{}.search_samples;
  int exhaustive_rounds = tn::TuneOptions{}.exhaustive_rounds;
  int verify_rounds = tn::TuneOptions{}.verify_rounds;
};

int command_tune(const SceneOptions& scene_options, const TuneCommand& command,
                 const std::string& command_line) {
  if (command.threads < 0) throw cl::InputError("--threads must be >= 0");
  if (command.max_chunk < 1) throw cl::InputError("--max-chunk must be >= 1");
  if (!command.json_out.empty()) cl::check_writable(command.json_out);
  tn::TuneOptions options;
  options.threads = cl::resolve_threads(command.threads);
  options.predict_only = command.predict_only;
  options.exhaustive = command.exhaustive;
  options.tolerance = command.tolerance;
  options.search_samples = command.search_samples;
  options.exhaustive_rounds = command.exhaustive_rounds;
  options.verify_rounds = command.verify_rounds;
  if (command.tolerance > 0) options.precisions.push_back(cl::Precision::kFloat);
  options.chunk_grid = tn::log2_chunk_grid(command.max_chunk);
  options.orders.clear();
  for (const auto& order : split_list(command.orders))
    options.orders.push_back(cl::parse_order(order));
  auto [scene, scene_record] = scene_options.load();
  tn::TuningCache cache(command.cache_file.empty() ? tn::TuningCache::default_path()
                                                   : command.cache_file);
  const tn::Calibration calibration =
      machine_calibration(cache, options, options.threads, command.recalibrate);
  const tn::TuneReport report =
      tn::tune(scene, scene_record, scene_options.diameter, options, calibration, command_line);
  for (const auto& method : report.json["methods"]) {
    std::string measured = "not measured";
    if (method.contains("measured")) {
      measured = fmt::format(
          "measured T_c {:.4f} s [{:.4f}, {:.4f}]  regret {:+.1f}% [{:+.1f}, {:+.1f}]",
          method["measured"]["median_s"].get<double>(),
          method["measured"]["ci95_low_s"].get<double>(),
          method["measured"]["ci95_high_s"].get<double>(), 100.0 * method["regret"].get<double>(),
          100.0 * method["regret_ci95"][0].get<double>(),
          100.0 * method["regret_ci95"][1].get<double>());
    }
    fmt::print("{:<11} {:<40} cost {:7.2f} s  {}\n", method["method"].get<std::string>(),
               method["variant"].get<std::string>(), method["tuning_cost_s"].get<double>(),
               measured);
  }
  for (const auto& c : report.json["classic"]) {
    fmt::print(
        "  classic {:<24} k = {:<7} {}\n", c["name"].get<std::string>(), c["chunk"].get<int>(),
        c.contains("regret") ? fmt::format("regret {:+.1f}%", 100.0 * c["regret"].get<double>())
                             : "");
  }
  for (const auto& p : report.json["predictions"]) {
    fmt::print("  {} threads: {} ({})\n", p["threads"].get<int>(), p["variant"].get<std::string>(),
               p["label"].get<std::string>());
  }
  if (!command.predict_only) {
    cache.store_choice(scene_record, scene_options.diameter, options.threads, report.chosen, 0.0);
  }
  if (!command.json_out.empty()) {
    cl::write_file_atomically(command.json_out,
                              [&](std::ostream& out) { out << report.json.dump(2) << '\n'; });
  }
  return 0;
}

int command_variants() {
  fmt::print("{}\n", cl::variants_help());
  fmt::print("The paper's configurations:\n");
  for (const auto& v : cl::paper_variants()) fmt::print("  {}\n", cl::to_string(v));
  fmt::print("\nEvery loop/order/stencil (schedules as above, any k):\n");
  cl::VariantSpace space = cl::all_variants({});
  for (const auto& v : cl::enumerate(space)) fmt::print("  {}\n", cl::to_string(v));
  return 0;
}

// The main job: every paper variant (and ours) on a small clustered scene, at 1 thread and at
// every core, as a table like the paper's.
int command_demo(SceneOptions scene_options, int repeat) {
  if (repeat < 1) throw cl::InputError("--repeat must be >= 1");
  if (!scene_options.diameter_given) {
    scene_options.diameter = 1.0 / 200.0;
    scene_options.diameter_given = true;
  }
  auto [scene, scene_record] = scene_options.load();
  const int cores = omp_get_num_procs();
  std::vector<cl::Variant> variants = cl::paper_variants();
  variants.push_back(cl::parse_variant("particle/sorted/half/static,200"));
  variants.push_back(cl::parse_variant("particle/morton/half/static,200"));
  fmt::print("Clustered scene: N = {}, D = {}, seed {}; {} cores; median of {} runs\n\n",
             scene.size(), scene_options.diameter, scene_options.seed, cores, repeat);
  fmt::print("{:<36} {:>7} {:>10} {:>10} {:>10} {:>8} {:>12}\n", "variant", "threads", "T_s [s]",
             "T_c [s]", "T_ALL [s]", "speedup", "contacts");
  cl::ContactDetector detector;
  std::optional<cl::ContactList> reference;
  bool all_equal = true;
  for (const auto& variant : variants) {
    double serial = 0.0;
    for (const int threads : {1, cores}) {
      if (threads == cores && cores == 1) break;
      cl::DetectOptions options{variant, scene_options.diameter, threads, nullptr};
      tn::MeasureOptions measure;
      measure.repetition.warmup = 1;
      measure.repetition.repeat = repeat;
      const tn::RunRecord r =
          tn::measure_detection(detector, scene, scene_record, options, measure);
      const tn::RunAggregates& a = *r.aggregates;
      if (threads == 1) serial = a.total_s.median;
      fmt::print("{:<36} {:>7} {:>10.4f} {:>10.4f} {:>10.4f} {:>8.2f} {:>12}\n",
                 cl::to_string(variant), threads, a.setup_s.median, a.detect_s.median,
                 a.total_s.median, serial / a.total_s.median, r.work->contact_pairs);
      cl::ContactList contacts = detector.canonical_contacts();
      if (!reference) {
        reference = std::move(contacts);
      } else if (contacts != *reference) {
        all_equal = false;
      }
    }
  }
  fmt::print("\nContact lists identical across all variants and thread counts: {}\n",
             all_equal ? "yes" : "NO");
  return all_equal ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"contactlab: particle contact detection — variants, measurement, tuning"};
  app.require_subcommand(1);
  std::string command_line;
  for (int i = 0; i < argc; ++i) command_line += (i ? " " : "") + std::string(argv[i]);

  SceneOptions scene_options;
  std::string scene_out;
  CLI::App* scene = app.add_subcommand("scene", "generate a scene and write it to a file");
  scene_options.add_to(*scene, false);
  scene->add_option("--out", scene_out, "output file: .csv/.txt text, anything else binary")
      ->required();

  SceneOptions detect_scene;
  DetectCommand detect_command;
  CLI::App* detect = app.add_subcommand("detect", "detect contacts with one variant");
  detect_scene.add_to(*detect, true);
  detect->add_option("--variant", detect_command.variant,
                     "loop/order[/stencil]/schedule[/float], or auto (the tuner's cached choice)");
  detect->add_option("--cache", detect_command.cache_file, "tuning cache file for --variant auto");
  detect->add_option("--threads", detect_command.threads, "OpenMP threads (0 = all)");
  detect->add_option("--repeat", detect_command.repeat, "timed repetitions");
  detect->add_option("--warmup", detect_command.warmup, "untimed runs first");
  detect->add_flag(
      "--adaptive", detect_command.adaptive,
      "repeat until the median's 95% interval is within --target-ci (--repeat = minimum)");
  detect->add_option("--target-ci", detect_command.target_ci,
                     "adaptive: target relative half-width of the median's interval (0.02 = 2%)");
  detect->add_option("--time-budget", detect_command.time_budget,
                     "adaptive: seconds before giving up");
  detect->add_option("--max-repeat", detect_command.max_repeat, "adaptive: most timed repetitions");
  detect->add_flag("--papi", detect_command.papi,
                   "count L1/L2 data-cache misses per thread with PAPI");
  detect->add_option("--papi-events", detect_command.papi_events,
                     "count these PAPI events instead (comma-separated, e.g. perf::TASK-CLOCK)");
  detect->add_option(
      "--cache-sim", detect_command.cache_sim,
      "simulate caches under valgrind: host, fx10, or custom:L1SIZE,WAYS,LINE:L2SIZE,WAYS,LINE");
  detect->add_option("--contacts-out", detect_command.contacts_out, "CSV of contacts i,j (i < j)");
  detect->add_option("--json", detect_command.json_out, "result file (docs/result-schema.md)");

  app.add_subcommand("variants", "list every variant and its parameters");

  std::string sweep_config;
  tn::SweepOptions sweep_options;
  CLI::App* sweep = app.add_subcommand("sweep", "measure every point of an experiment config");
  sweep->add_option("config", sweep_config, "experiment config (JSON, docs/experiments.md)")
      ->required();
  sweep->add_option("--out", sweep_options.out, "result file")->required();
  sweep->add_flag("--resume", sweep_options.resume,
                  "keep the finished points of --out and run the rest");

  SceneOptions tune_scene;
  TuneCommand tune_command;
  CLI::App* tune = app.add_subcommand("tune", "choose the variant and chunk size (docs/tuning.md)");
  tune_scene.add_to(*tune, true);
  tune->add_option("--threads", tune_command.threads, "threads to tune for (0 = all cores)");
  tune->add_option("--json", tune_command.json_out, "tuning report (JSON)");
  tune->add_option("--cache", tune_command.cache_file, "tuning cache file");
  tune->add_flag("--predict-only", tune_command.predict_only,
                 "the model alone: no timed run on the scene");
  tune->add_flag("--exhaustive", tune_command.exhaustive, "also sweep every chunk (ground truth)");
  tune->add_flag("--recalibrate", tune_command.recalibrate, "fit the machine's cost model again");
  tune->add_option("--tolerance", tune_command.tolerance,
                   "wrong contact pairs allowed (single precision)");
  tune->add_option("--max-chunk", tune_command.max_chunk, "largest chunk of the grid 1, 2, 4, ...");
  tune->add_option("--orders", tune_command.orders, "orders to screen, comma-separated");
  tune->add_option("--search-samples", tune_command.search_samples,
                   "timed runs per chunk the search evaluates")
      ->check(CLI::PositiveNumber);
  tune->add_option("--exhaustive-rounds", tune_command.exhaustive_rounds,
                   "rounds over the chunk grid in the exhaustive sweep (one run per chunk each)")
      ->check(CLI::PositiveNumber);
  tune->add_option("--verify-rounds", tune_command.verify_rounds,
                   "rounds of the final verification (every choice timed once per round)")
      ->check(CLI::PositiveNumber);

  SceneOptions demo_scene;
  int demo_repeat = 3;
  CLI::App* demo =
      app.add_subcommand("demo", "time the paper's variants on a small clustered scene");
  demo_scene.add_to(*demo, false);
  demo->add_option("--repeat", demo_repeat, "timed repetitions");

  try {
    app.parse(argc, argv);
    if (*scene) return command_scene(scene_options, scene_out);
    if (*detect) return command_detect(detect_scene, detect_command, command_line);
    if (*demo) return command_demo(demo_scene, demo_repeat);
    if (*sweep) {
      sweep_options.progress = true;
      sweep_options.command_line = command_line;
      return command_sweep(sweep_config, sweep_options);
    }
    if (*tune) return command_tune(tune_scene, tune_command, command_line);
    return command_variants();
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const cl::InputError& e) {
    fmt::print(stderr, "contactlab: error: {}\n", e.what());
    return 2;
  } catch (const std::bad_alloc&) {
    fmt::print(stderr, "contactlab: error: out of memory\n");
    return 3;
  }
}
