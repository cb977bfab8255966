// `contactlab detect`: detect contacts with one variant, measured (times, counters), printed
// and optionally written as a result file.
#include <fmt/core.h>

#include <memory>
#include <optional>

#include "cli_shared.hpp"
#include "contactlab/kernels/atomic_file.hpp"
#include "contactlab/kernels/detector.hpp"
#include "contactlab/kernels/error.hpp"
#include "contactlab/tuner/auto_variant.hpp"
#include "contactlab/tuner/cache_sim.hpp"
#include "contactlab/tuner/context.hpp"
#include "contactlab/tuner/measure.hpp"
#include "contactlab/tuner/papi_counters.hpp"
#include "detect_mpi.hpp"

namespace contactlab::cli {
namespace {

namespace tn = contactlab::tuner;

struct DetectCommand {
  SceneOptions scene_;
  std::string variant_ = "particle/sorted/full/static,200";
  int threads_ = 0;
  RepetitionPolicy repetition_;  // its defaults are the options' defaults
  bool papi_ = false;
  std::string papi_events_;
  std::string cache_sim_;
  std::string cache_file_;  // tuning cache for --variant auto
  std::string contacts_out_;
  std::string json_out_;
  std::string command_line_;
  MpiCliOptions mpi_;
  std::vector<CLI::Option*> adaptive_options_;  // --mpi repeats a fixed count: not these

  void add_to(CLI::App& sub);
  void check() const;
  [[maybe_unused]] void check_mpi() const;  // unused in a build without MPI
  int run() const;
};

void DetectCommand::add_to(CLI::App& sub) {
  scene_.add_to(sub, true);
  sub.add_option("--variant", variant_,
                 "loop/order[/stencil]/schedule[/float], or auto (the tuner's cached choice)");
  sub.add_option("--cache", cache_file_, "tuning cache file for --variant auto");
  sub.add_option("--threads", threads_, "OpenMP threads (0 = all)");
  sub.add_option("--repeat", repetition_.repeat, "timed repetitions");
  sub.add_option("--warmup", repetition_.warmup, "untimed runs first");
  adaptive_options_.push_back(sub.add_flag(
      "--adaptive", repetition_.adaptive,
      "repeat until the median's 95% interval is within --target-ci (--repeat = minimum)"));
  adaptive_options_.push_back(
      sub.add_option("--target-ci", repetition_.target_relative_half_width,
                     "adaptive: target relative half-width of the median's interval (0.02 = 2%)"));
  adaptive_options_.push_back(sub.add_option("--time-budget", repetition_.time_budget_s,
                                             "adaptive: seconds before giving up"));
  adaptive_options_.push_back(
      sub.add_option("--max-repeat", repetition_.max_repeat, "adaptive: most timed repetitions"));
  sub.add_flag("--papi", papi_, "count L1/L2 data-cache misses per thread with PAPI");
  sub.add_option("--papi-events", papi_events_,
                 "count these PAPI events instead (comma-separated, e.g. perf::TASK-CLOCK)");
  sub.add_option(
      "--cache-sim", cache_sim_,
      "simulate caches under valgrind: host, fx10, or custom:L1SIZE,WAYS,LINE:L2SIZE,WAYS,LINE");
  sub.add_option("--contacts-out", contacts_out_, "CSV of contacts i,j (i < j)");
  sub.add_option("--json", json_out_, "result file (docs/result-schema.md)");
  mpi_.add_to(sub,
              "run over the MPI processes (under mpirun): replicated (the paper) or decomposed");
}

// What --mpi cannot combine with (a fixed number of repetitions, without counters).
void DetectCommand::check_mpi() const {
  if (threads_ < 0) throw InputError("--threads must be >= 0");
  if (repetition_.repeat < 1) throw InputError("--repeat must be >= 1");
  if (repetition_.warmup < 0) throw InputError("--warmup must be >= 0");
  for (const CLI::Option* option : adaptive_options_) {
    if (option->count() > 0) {
      throw InputError("--mpi repeats a fixed count: " + option->get_name() +
                       " is not supported with it");
    }
  }
  if (papi_ || !papi_events_.empty() || !cache_sim_.empty()) {
    throw InputError("--mpi does not support --papi, --papi-events or --cache-sim");
  }
}

// Option values that are wrong whatever the scene: rejected before any work.
void DetectCommand::check() const {
  if (repetition_.repeat < 1) throw InputError("--repeat must be >= 1");
  if (repetition_.warmup < 0) throw InputError("--warmup must be >= 0");
  if (threads_ < 0) throw InputError("--threads must be >= 0");
  if (repetition_.adaptive) {
    if (!(repetition_.target_relative_half_width > 0.0 &&
          repetition_.target_relative_half_width < 1.0)) {
      throw InputError(fmt::format("--target-ci must be in (0, 1) (a fraction: 0.02 = 2%), got {}",
                                   repetition_.target_relative_half_width));
    }
    if (!(repetition_.time_budget_s > 0.0)) throw InputError("--time-budget must be > 0 seconds");
    if (repetition_.max_repeat < repetition_.repeat)
      throw InputError("--max-repeat must be >= --repeat");
  }
}

void print_summary(const char* name, const Summary& s) {
  const std::string interval =
      s.count < 2 ? std::string("no interval from 1 sample")
                  : fmt::format("[{:.6f}, {:.6f}] covers the median with {:.1f}%", s.interval.low,
                                s.interval.high, 100.0 * s.interval.coverage);
  fmt::print("{:<6} median {:.6f} s  {}  min {:.6f}  max {:.6f}\n", name, s.median, interval, s.min,
             s.max);
}

void print_run(const tn::RunRecord& run, std::size_t particles) {
  const tn::RunAggregates& a = *run.aggregates;
  const tn::RunWork& w = *run.work;
  const auto hashed = run.work_counts.find("hashed_index");
  const bool hashed_index = hashed != run.work_counts.end() && hashed->second != 0;
  fmt::print("variant {}  threads {}  N {}  grid {}x{}x{} ({} index)  max occupancy {}\n",
             run.parameters.variant, run.parameters.threads, particles, w.grid[0], w.grid[1],
             w.grid[2], hashed_index ? "hashed" : "dense", w.max_cell_occupancy);
  fmt::print("{} repetitions after {} warm-up ({}), T_ALL = T_s + T_c:\n", a.repetitions,
             a.warmup_runs, to_string(a.stop_reason));
  print_summary("T_s", a.setup_s);
  print_summary("T_c", a.detect_s);
  print_summary("T_ALL", a.total_s);
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
}

int DetectCommand::run() const {
  if (!mpi_.mode.empty()) {
#ifdef CONTACTLAB_HAVE_MPI
    MpiDetectRequest request;
    request.mpi = mpi_;
    request.scene = &scene_;
    request.variant = variant_;
    request.cache_file = cache_file_;
    request.threads = threads_;
    request.warmup = repetition_.warmup;
    request.repeat = repetition_.repeat;
    request.contacts_out = contacts_out_;
    request.json_out = json_out_;
    request.command_line = command_line_;
    request.check_options = [this] { check_mpi(); };
    return run_detect_mpi(request);
#else
    throw InputError("this contactlab was built without MPI (--mpi " + mpi_.mode + ")");
#endif
  }
  check();
  const bool automatic = variant_ == "auto";
  const int threads = resolve_threads(threads_);
  if (automatic && !cache_sim_.empty()) {
    throw InputError("--cache-sim needs an explicit --variant (not auto)");
  }

  std::optional<tn::CacheGeometry> geometry;
  if (!cache_sim_.empty()) geometry = tn::parse_cache_geometry(cache_sim_);
  if (!contacts_out_.empty()) prepare_output_file(contacts_out_);
  if (!json_out_.empty()) prepare_output_file(json_out_);
  std::optional<tn::PapiCounters> papi;
  if (papi_ || !papi_events_.empty()) {
    papi.emplace(papi_events_.empty() ? std::vector<std::string>{} : split_list(papi_events_));
  }
  auto [scene, scene_record] = scene_.load();
  const double diameter = scene_.diameter_;
  const Variant variant = automatic ? tn::auto_variant(scene, scene_record, diameter, threads,
                                                       cache_file_, command_line_)
                                    : parse_variant(variant_);

  tn::ResultFile result;
  result.context = tn::collect_context(command_line_, threads);
  for (const auto& w : result.context.warnings) fmt::print(stderr, "contactlab: warning: {}\n", w);

  DetectOptions options{variant, diameter, threads, nullptr};
  tn::MeasureOptions measure;
  measure.repetition = repetition_;
  measure.papi = papi ? &*papi : nullptr;
  ContactDetector detector;
  tn::RunRecord run = tn::measure_detection(detector, scene, scene_record, options, measure);

  if (geometry) {
    fmt::print(stderr, "contactlab: simulating the {} caches under valgrind (slow)...\n",
               geometry->name);
    run.counters.push_back(
        tn::simulate_detection_caches(scene, diameter, variant, threads, *geometry));
  }
  print_run(run, scene.size());

  if (!contacts_out_.empty()) write_pairs_csv(detector.canonical_contacts(), contacts_out_);
  const bool ok = run.status == tn::RunStatus::kOk;
  result.runs.push_back(std::move(run));
  if (!json_out_.empty()) tn::write_result_file(json_out_, result);
  return ok ? 0 : 1;
}

}  // namespace

Subcommand add_detect_command(CLI::App& app, const std::string& command_line) {
  auto command = std::make_shared<DetectCommand>();
  command->command_line_ = command_line;
  CLI::App* sub = app.add_subcommand("detect", "detect contacts with one variant");
  command->add_to(*sub);
  return {sub, [command] { return command->run(); }};
}

}  // namespace contactlab::cli
