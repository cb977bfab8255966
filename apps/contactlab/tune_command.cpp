// `contactlab tune`: choose the variant and chunk size for a scene (docs/tuning.md), print the
// methods side by side, cache the choice and optionally write the report.
#include <fmt/core.h>

#include <memory>

#include "cli_shared.hpp"
#include "contactlab/kernels/atomic_file.hpp"
#include "contactlab/kernels/detector.hpp"
#include "contactlab/kernels/error.hpp"
#include "contactlab/tuner/auto_variant.hpp"
#include "contactlab/tuner/tune.hpp"
#include "detect_mpi.hpp"

namespace contactlab::cli {
namespace {

namespace tn = contactlab::tuner;

struct TuneCommand {
  SceneOptions scene_;
  int threads_ = 0;
  std::string json_out_;
  std::string cache_file_;
  bool predict_only_ = false;
  bool exhaustive_ = false;
  bool recalibrate_ = false;
  std::uint64_t tolerance_ = 0;
  bool float_ = false;
  int max_chunk_ = 65536;
  std::string orders_ = "sorted";
  std::string grids_ = "auto";
  int search_samples_ = tn::TuneOptions{}.search_samples;
  int exhaustive_rounds_ = tn::TuneOptions{}.exhaustive_rounds;
  int verify_rounds_ = tn::TuneOptions{}.verify_rounds;
  CLI::Option* verify_rounds_option_ = nullptr;
  std::string command_line_;
  MpiCliOptions mpi_;
  DemTuneRequest dem_;  // --dem: tune the DEM force pass instead of detection

  void add_to(CLI::App& sub);
  void check() const;
  tn::TuneOptions options() const;
  int run() const;
};

void TuneCommand::add_to(CLI::App& sub) {
  scene_.add_to(sub, true);
  sub.add_option("--threads", threads_, "threads to tune for (0 = all cores)");
  sub.add_option("--json", json_out_, "tuning report (JSON)");
  sub.add_option("--cache", cache_file_, "tuning cache file");
  sub.add_flag("--predict-only", predict_only_, "the model alone: no timed run on the scene");
  sub.add_flag("--exhaustive", exhaustive_, "also sweep every chunk (ground truth)");
  sub.add_flag("--recalibrate", recalibrate_, "fit the machine's cost model again");
  sub.add_flag("--float", float_,
               "screen the single-precision variants too (exact: near-ties in double)");
  sub.add_option("--tolerance", tolerance_, "wrong contact pairs allowed (implies --float)");
  sub.add_option("--max-chunk", max_chunk_, "largest chunk of the grid 1, 2, 4, ...");
  sub.add_option("--orders", orders_,
                 "orders to screen, comma-separated (sorted, morton, unsorted)");
  sub.add_option("--grids", grids_,
                 "cell indexes to screen, comma-separated: auto (default), dense, hashed");
  sub.add_option("--search-samples", search_samples_, "timed runs per chunk the search evaluates");
  sub.add_option("--exhaustive-rounds", exhaustive_rounds_,
                 "rounds over the chunk grid in the exhaustive sweep (one run per chunk each)");
  verify_rounds_option_ =
      sub.add_option("--verify-rounds", verify_rounds_,
                     "rounds of the final verification (every choice timed once per round; "
                     "--dem: 3 unless given)");
  mpi_.add_to(sub,
              "tune each MPI rank's part (under mpirun): replicated (the paper) or decomposed");
  sub.add_option("--dem", dem_.config,
                 "tune the DEM force pass of this config (model, search; --exhaustive, "
                 "--predict-only, --verify-rounds apply)");
  sub.add_option("--restart", dem_.restart, "--dem: start from this checkpoint of the config");
  sub.add_option("--dem-steps", dem_.steps,
                 "--dem: timed steps per run (calibration, search, exhaustive, verification; 200)");
}

void TuneCommand::check() const {
  if (threads_ < 0) throw InputError("--threads must be >= 0");
  if (max_chunk_ < 1) throw InputError("--max-chunk must be >= 1");
  // Here, not by CLI11's PositiveNumber, whose message printed the range up to DBL_MAX in full.
  if (search_samples_ < 1) throw InputError("--search-samples must be >= 1");
  if (exhaustive_rounds_ < 1) throw InputError("--exhaustive-rounds must be >= 1");
  if (verify_rounds_ < 1) throw InputError("--verify-rounds must be >= 1");
}

tn::TuneOptions TuneCommand::options() const {
  tn::TuneOptions options;
  options.threads = resolve_threads(threads_);
  options.predict_only = predict_only_;
  options.exhaustive = exhaustive_;
  options.tolerance = tolerance_;
  options.search_samples = search_samples_;
  options.exhaustive_rounds = exhaustive_rounds_;
  options.verify_rounds = verify_rounds_;
  if (float_ || tolerance_ > 0) options.precisions.push_back(Precision::kFloat);
  options.chunk_grid = tn::log2_chunk_grid(max_chunk_);
  options.orders.clear();
  for (const auto& order : split_list(orders_)) options.orders.push_back(parse_order(order));
  options.grids.clear();
  for (const auto& grid : split_list(grids_)) options.grids.push_back(parse_grid_index(grid));
  return options;
}

// One line per method, then the classic schedules and the predictions for other thread counts.
void print_report(const tn::TuneDocument& report) {
  for (const tn::MethodEntry& method : report.methods) {
    std::string measured = "not measured";
    if (method.measured) {
      measured =
          fmt::format("measured T_c {:.4f} s [{:.4f}, {:.4f}]  regret {:+.1f}% [{:+.1f}, {:+.1f}]",
                      method.measured->median_s, method.measured->ci95_low_s,
                      method.measured->ci95_high_s, 100.0 * method.regret.value_or(0.0),
                      100.0 * method.regret_ci95.value()[0], 100.0 * method.regret_ci95.value()[1]);
    }
    fmt::print("{:<11} {:<40} cost {:7.2f} s  {}\n", method.method, method.variant,
               method.tuning_cost_s, measured);
  }
  for (const tn::ClassicEntry& c : report.classic) {
    fmt::print("  classic {:<24} k = {:<7} {}\n", c.name, c.chunk,
               c.regret ? fmt::format("regret {:+.1f}%", 100.0 * *c.regret) : "");
  }
  for (const tn::Prediction& p : report.predictions) {
    fmt::print("  {} threads: {} ({})\n", p.threads, p.variant, p.label);
  }
}

int TuneCommand::run() const {
  if (!dem_.config.empty()) {
    check();
    DemTuneRequest request = dem_;
    request.threads = resolve_threads(threads_);
    request.json_out = json_out_;
    request.predict_only = predict_only_;
    request.exhaustive = exhaustive_;
    if (verify_rounds_option_->count() > 0) request.verify_rounds = verify_rounds_;
    return tune_dem(request);
  }
  if (!mpi_.mode.empty()) {
#ifdef CONTACTLAB_HAVE_MPI
    MpiTuneRequest request;
    request.mpi = mpi_;
    request.scene = &scene_;
    request.cache_file = cache_file_;
    request.json_out = json_out_;
    request.command_line = command_line_;
    request.recalibrate = recalibrate_;
    request.check_options = [this] { check(); };
    request.options = [this] { return options(); };
    request.print = print_report;
    return run_tune_mpi(request);
#else
    throw InputError("this contactlab was built without MPI (--mpi " + mpi_.mode + ")");
#endif
  }
  check();
  if (!json_out_.empty()) prepare_output_file(json_out_);
  const tn::TuneOptions options = this->options();
  auto [scene, scene_record] = scene_.load();
  const double diameter = scene_.diameter_;
  tn::TuningCache cache(cache_file_.empty() ? tn::TuningCache::default_path() : cache_file_);
  const tn::Calibration calibration =
      tn::machine_calibration(cache, options, options.threads, recalibrate_);
  const tn::TuneReport report =
      tn::tune(scene, scene_record, diameter, options, calibration, command_line_);
  print_report(report.document);
  if (!predict_only_) {
    cache.store_choice(scene_record, diameter, options.threads, report.chosen, 0.0);
  }
  if (!json_out_.empty()) {
    write_file_atomically(json_out_, [&](std::ostream& out) {
      out << tn::to_json_value(report.document).dump(2) << '\n';
    });
  }
  return 0;
}

}  // namespace

Subcommand add_tune_command(CLI::App& app, const std::string& command_line) {
  auto command = std::make_shared<TuneCommand>();
  command->command_line_ = command_line;
  CLI::App* sub = app.add_subcommand("tune", "choose the variant and chunk size (docs/tuning.md)");
  command->add_to(*sub);
  return {sub, [command] { return command->run(); }};
}

}  // namespace contactlab::cli
