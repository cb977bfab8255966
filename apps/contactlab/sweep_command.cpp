// `contactlab sweep`: measure every point of an experiment config (docs/experiments.md).
#include <fmt/core.h>

#include <memory>

#include "cli_shared.hpp"
#include "contactlab/tuner/experiment.hpp"
#include "contactlab/tuner/sweep.hpp"

namespace contactlab::cli {
namespace {

struct SweepCommand {
  std::string config_;
  tuner::SweepOptions options_;

  int run() const {
    const tuner::Experiment experiment = tuner::read_experiment(config_);
    const tuner::SweepSummary summary = tuner::run_sweep(experiment, options_);
    fmt::print("{}: {} points{}, {} already done, {} ok, {} invalid, {} failed, {:.1f} s -> {}\n",
               experiment.name, summary.points,
               experiment.rounds > 1 ? fmt::format(" x {} rounds", experiment.rounds) : "",
               summary.skipped, summary.ok, summary.invalid, summary.failed, summary.seconds,
               options_.out);
    return summary.failed || summary.invalid ? 1 : 0;
  }
};

}  // namespace

Subcommand add_sweep_command(CLI::App& app, const std::string& command_line) {
  auto command = std::make_shared<SweepCommand>();
  command->options_.progress = true;
  command->options_.command_line = command_line;
  CLI::App* sub = app.add_subcommand("sweep", "measure every point of an experiment config");
  sub->add_option("config", command->config_, "experiment config (JSON, docs/experiments.md)")
      ->required();
  sub->add_option("--out", command->options_.out, "result file")->required();
  sub->add_flag("--resume", command->options_.resume,
                "keep the finished points of --out, run the rest (same machine and build)");
  return {sub, [command] { return command->run(); }};
}

}  // namespace contactlab::cli
