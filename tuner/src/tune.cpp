// tune(): runs the registered tuning methods in order on a MeasuredKernel, prices the classic
// chunk formulas on the structure they tuned, and verifies every choice by timing them alike
// (docs/tuning.md); the report is keyed by method name.
#include "contactlab/tuner/tune.hpp"

#include <fmt/core.h>
#include <omp.h>

#include <algorithm>
#include <map>
#include <numeric>
#include <optional>
#include <random>

#include "contactlab/kernels/error.hpp"
#include "contactlab/support/statistics.hpp"
#include "contactlab/tuner/context.hpp"
#include "contactlab/tuner/tuning_method.hpp"
#include "contactlab/tuner_model/chunk_formulas.hpp"

namespace contactlab::tuner {
namespace {

VerifiedTiming timing_of(const std::vector<double>& samples) {
  const Summary s = summarize(samples);
  return {s.median, s.interval.low, s.interval.high, samples};
}

// The final verification's timings: `rounds` samples of every distinct variant among the
// named contenders, taken round by round in a new random order each round (fixed seed).
class Verification {
 public:
  Verification(MeasuredKernel& kernel, int threads,
               const std::vector<std::pair<std::string, Variant>>& contenders, int rounds) {
    for (const auto& [name, variant] : contenders) {
      const auto found = std::find(distinct_.begin(), distinct_.end(), variant);
      index_of_[name] = static_cast<std::size_t>(found - distinct_.begin());
      if (found == distinct_.end()) distinct_.push_back(variant);
    }
    samples_.resize(distinct_.size());
    std::vector<std::size_t> order(distinct_.size());
    std::iota(order.begin(), order.end(), std::size_t{0});
    std::mt19937_64 random(20131001);
    for (const Variant& variant : distinct_) kernel.run(variant, threads);  // warm-up
    for (int round = 0; round < rounds; ++round) {
      std::shuffle(order.begin(), order.end(), random);
      for (const std::size_t i : order) {
        samples_[i].push_back(kernel.samples(distinct_[i], threads, 1).front());
      }
    }
    // The fastest: the smallest median slowdown against each round's fastest. Pairwise median
    // ratios are not transitive (noise can make a cycle in which each contender beats the
    // next); one number per contender is, so that every regret against the fastest is >= 0.
    slowdowns_.emplace(samples_);
  }
  bool has(const std::string& name) const { return index_of_.count(name) != 0; }
  const std::vector<double>& samples_of(const std::string& name) const {
    return samples_[index_of_.at(name)];
  }
  const Variant& best() const { return distinct_[slowdowns_->fastest()]; }
  std::size_t distinct_count() const { return distinct_.size(); }

  // The verified timings of one contender and its regrets, into its report entry.
  void attach(Verified& target, const std::string& name) const {
    target.measured = timing_of(samples_of(name));
    const RoundSlowdowns::Ratio to_best =
        slowdowns_->relative(index_of_.at(name), slowdowns_->fastest());
    target.regret = to_best.value - 1.0;
    target.regret_ci95 = {to_best.low - 1.0, to_best.high - 1.0};
    if (has("exhaustive")) {
      const PairedRatio to_exhaustive = paired_ratio(samples_of(name), samples_of("exhaustive"));
      target.vs_exhaustive =
          RatioToExhaustive{to_exhaustive.median - 1.0,
                            {to_exhaustive.interval.low - 1.0, to_exhaustive.interval.high - 1.0}};
    }
  }

 private:
  std::vector<Variant> distinct_;
  std::map<std::string, std::size_t> index_of_;
  std::vector<std::vector<double>> samples_;
  std::optional<RoundSlowdowns> slowdowns_;
};

// Classic formulas for the structure that is tuned, as report entries. A kernel of several
// parts takes the first part's chunks (each part's come from its own work), so that all verify
// the same variants.
std::vector<ClassicEntry> classic_entries(MeasuredKernel& kernel, const PricedStructure& structure,
                                          int threads) {
  std::vector<ClassicEntry> classic;
  const WorkView work{structure.work.tests, structure.work.homes, structure.work.builds};
  std::vector<NamedChunk> chunks = classic_chunks(work, threads, structure.costs);
  std::vector<int> k;
  k.reserve(chunks.size());
  for (const NamedChunk& c : chunks) k.push_back(c.chunk);
  kernel.from_first_part(k);
  for (std::size_t i = 0; i < chunks.size(); ++i) chunks[i].chunk = k[i];
  for (const NamedChunk& c : chunks) {
    ClassicEntry entry;
    entry.name = c.name;
    entry.chunk = c.chunk;
    entry.inputs = c.inputs;
    entry.structure = structure_key(structure.variant);
    classic.push_back(std::move(entry));
  }
  return classic;
}

}  // namespace

TuneReport tune_kernel(MeasuredKernel& kernel, const SceneRecord& scene,
                       std::optional<double> diameter, const TuneOptions& options,
                       const Calibration& calibration, const std::string& command_line) {
  const int threads = resolve_threads(options.threads);
  if (options.chunk_grid.empty()) throw InputError("tune: the chunk grid is empty");
  if (options.search_samples < 1 || options.exhaustive_rounds < 1 || options.verify_rounds < 1) {
    throw InputError(fmt::format(
        "tune: search samples ({}), exhaustive rounds ({}) and verification rounds ({}) must be "
        ">= 1",
        options.search_samples, options.exhaustive_rounds, options.verify_rounds));
  }
  TuneReport result;
  TuneDocument& report = result.document;
  report.context = collect_context(command_line, threads);
  report.scene = scene;
  report.diameter = diameter;
  report.threads = threads;
  report.chunk_grid = options.chunk_grid;
  report.calibration = {calibration.source, calibration.seconds};

  TuningState state{kernel, options, calibration, threads, report};
  for (const auto& method : tuning_methods()) {
    if (!method->enabled(options) || (options.predict_only && method->times_runs())) continue;
    report.methods.push_back(method->choose(state));
  }
  const PricedStructure& tuned = state.tuned ? *state.tuned : *state.model_best;
  report.classic = classic_entries(kernel, tuned, threads);
  // What --variant auto uses: the last choice (the search's; the model's with predict_only).
  result.chosen = state.choices.back().second;
  if (options.predict_only) return result;

  // Verification: each method's choice, each classic formula's k and the model's best schedule
  // of every structure it priced, timed alike, every distinct variant once per round in a new
  // random order. Comparisons are within rounds (drift of the machine cancels: each time over
  // the round's fastest), and regret is against the fastest verified choice, not the minimum of the
  // exhaustive sweep's own medians (biased low by noise). The structures are there because the
  // methods choose among them: a structure no method chose could otherwise be faster unseen.
  std::vector<std::pair<std::string, Variant>> contenders = state.choices;
  for (ClassicEntry& c : report.classic) {
    const Variant variant = with_schedule(tuned.variant, state.tuned_kind, c.chunk);
    c.variant = to_string(variant);
    contenders.emplace_back("classic:" + c.name, variant);
  }
  for (const PricedStructure& s : state.structures) {
    contenders.emplace_back("structure:" + to_string(s.model_choice), s.model_choice);
  }
  const Verification verified(kernel, threads, contenders, options.verify_rounds);
  report.verification = VerificationSummary{
      options.verify_rounds, static_cast<int>(verified.distinct_count()),
      to_string(verified.best()),
      "fastest verified choice (smallest median over rounds of time / the round's fastest time); "
      "regret = that median over the fastest's - 1, 95% bootstrap interval over rounds"};
  for (ClassicEntry& entry : report.classic) verified.attach(entry, "classic:" + entry.name);
  for (MethodEntry& entry : report.methods) {
    verified.attach(entry, entry.method);
    if (entry.method != "model" || !entry.structures) continue;
    for (nlohmann::json& row : *entry.structures) {  // each structure's verified timing
      Verified timing;
      verified.attach(timing, "structure:" + row.at("variant").get<std::string>());
      row.update(to_json_value(timing));
    }
  }
  return result;
}

TuneReport tune(const Scene& scene, const SceneRecord& scene_record, double diameter,
                const TuneOptions& options, const Calibration& calibration,
                const std::string& command_line) {
  DetectionKernel kernel(scene, diameter);
  return tune_kernel(kernel, scene_record,
                     scene.has_diameters() ? std::nullopt : std::optional<double>(diameter),
                     options, calibration, command_line);
}

}  // namespace contactlab::tuner
