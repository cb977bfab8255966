// The tuning methods over a scripted kernel, whose run times are a function of the variant, so
// what each method must choose is known without timing anything real.
#include <gtest/gtest.h>

#include <functional>
#include <string>
#include <utility>

#include "contactlab/tuner/measured_kernel.hpp"
#include "contactlab/tuner/tune.hpp"

namespace contactlab::tuner {
namespace {

class ScriptedKernel final : public MeasuredKernel {
 public:
  explicit ScriptedKernel(std::function<double(const Variant&)> seconds)
      : seconds_(std::move(seconds)) {}
  std::string_view name() const override { return "scripted"; }
  std::string_view tuned_phase() const override { return "detect"; }
  KernelRun run(const Variant& variant, int) override {
    return {{{"detect", seconds_(variant)}}, {}};
  }
  // Equal iterations: the model prices every static partition alike and prefers the block.
  LoopWork iteration_work(const Variant&, int) override {
    LoopWork work;
    work.tests.assign(4096, 100);
    work.homes.assign(4096, 1);
    work.builds.assign(4096, 1);
    return work;
  }
  std::pair<std::uint64_t, std::uint64_t> wrong_results() override { return {0, 0}; }

 private:
  std::function<double(const Variant&)> seconds_;
};

TuneOptions one_structure() {
  TuneOptions options;
  options.threads = 2;
  options.loops = {LoopKind::kParticle};
  options.orders = {Order::kSorted};
  options.stencils = {Stencil::kFull};
  options.chunk_grid = {1, 2, 4, 8, 16, 32, 64, 128, 256};
  options.search_samples = 1;
  options.verify_rounds = 3;
  return options;
}

Calibration flat_costs() {
  Calibration calibration;
  calibration.source = "scripted";
  calibration.structures[structure_key(parse_variant("particle/sorted/full/static"))] = {};
  return calibration;
}

std::pair<const MethodEntry*, const MethodEntry*> model_and_search(const TuneReport& report) {
  return {report.document.method("model"), report.document.method("search")};
}

TEST(SearchMethod, ReachesTheModelsBlockScheduleOffTheChunkGrid) {
  // The block (static without a chunk size: thread 0 writes its rows in place) runs 20 % faster
  // than any chunk of the grid; the chunk search alone cannot reach it.
  ScriptedKernel kernel([](const Variant& v) {
    const bool block = v.schedule.kind == ScheduleKind::kStatic && v.schedule.chunk == 0;
    return block ? 1.0e-3 : 1.2e-3;
  });
  const TuneReport report =
      tune_kernel(kernel, SceneRecord{}, 0.01, one_structure(), flat_costs(), "test");
  const auto [model, search] = model_and_search(report);
  ASSERT_TRUE(model && search);
  ASSERT_EQ(model->variant, "particle/sorted/full/static");  // so the search weighs the block
  EXPECT_EQ(search->variant, "particle/sorted/full/static");
  EXPECT_EQ(to_string(report.chosen), "particle/sorted/full/static");
  EXPECT_DOUBLE_EQ(*search->regret, 0.0);
}

TEST(SearchMethod, KeepsAFasterChunkOverTheBlock) {
  ScriptedKernel kernel([](const Variant& v) {
    if (v.schedule.kind != ScheduleKind::kStatic) return 2.0e-3;
    return v.schedule.chunk == 0 ? 1.5e-3 : 1.0e-3 + 1e-6 * v.schedule.chunk;
  });
  const TuneReport report =
      tune_kernel(kernel, SceneRecord{}, 0.01, one_structure(), flat_costs(), "test");
  const auto [model, search] = model_and_search(report);
  ASSERT_TRUE(model && search);
  ASSERT_EQ(model->variant, "particle/sorted/full/static");  // so the search weighs the block
  EXPECT_NE(search->chunk, 0) << search->variant;
}

}  // namespace
}  // namespace contactlab::tuner
