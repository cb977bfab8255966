// The tuning methods as plug-ins: each has a name and chooses a variant of a MeasuredKernel;
// tuning_methods() registers them in the order tune() runs them, and the final verification
// times every method's choice and reports it under the method's name.
//
// Methods run in order and may stand on earlier ones (the search is seeded by the model and
// screens the structures it priced; the exhaustive sweep covers the search's structure and
// schedule kind): what they share is in TuningState. A new method is a class here plus one
// line in tuning_methods() (tuner/src/methods/registry.cpp).
#pragma once

#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "contactlab/kernels/variant.hpp"
#include "contactlab/tuner/measured_kernel.hpp"
#include "contactlab/tuner/tune.hpp"
#include "contactlab/tuner_model/chunk_search.hpp"
#include "contactlab/tuner_model/schedule_model.hpp"

namespace contactlab::tuner {

// A structure (a variant without its schedule) with its exact work, its calibrated costs and
// the model's best schedule for it.
struct PricedStructure {
  Variant variant;
  LoopWork work;
  MachineCosts costs;
  Variant model_choice;      // the structure with the model's best schedule
  double predicted_s = 0.0;  // the loop's best schedule + output_s
  std::vector<OutputCost> output;
  double output_s = 0.0;  // the output term (output_cost.hpp) at the tuned thread count
};

struct TuningState {
  TuningState(MeasuredKernel& kernel_, const TuneOptions& options_, const Calibration& calibration_,
              int threads_, TuneDocument& report_)
      : kernel(kernel_),
        options(options_),
        calibration(calibration_),
        threads(threads_),
        report(report_) {}

  MeasuredKernel& kernel;
  const TuneOptions& options;
  const Calibration& calibration;
  int threads = 1;
  TuneDocument& report;  // the tune.json document being written

  // Set by the model.
  std::vector<PricedStructure> structures;
  const PricedStructure* model_best = nullptr;
  double model_cost_s = 0.0;
  // Set by the search: the structure it tunes and the schedule kind it searched, and its
  // chunk-search options (the exhaustive sweep covers the same grid).
  const PricedStructure* tuned = nullptr;
  ScheduleKind tuned_kind = ScheduleKind::kStatic;
  ChunkSearchOptions search_options;
  // Each method's choice by name, in the order they ran.
  std::vector<std::pair<std::string, Variant>> choices;
};

class TuningMethod {
 public:
  virtual ~TuningMethod() = default;
  virtual std::string_view name() const = 0;
  // Whether the method times runs on the scene (--predict-only runs only those that do not).
  virtual bool times_runs() const = 0;
  virtual bool enabled(const TuneOptions& /*options*/) const { return true; }
  // Chooses; returns the method's entry of the report's "methods" (its verified timings and
  // regret are added later under the same name).
  virtual MethodEntry choose(TuningState& state) = 0;
};

const std::vector<std::unique_ptr<TuningMethod>>& tuning_methods();

// `structure` with schedule kind/chunk.
Variant with_schedule(Variant structure, ScheduleKind kind, int chunk);

}  // namespace contactlab::tuner
