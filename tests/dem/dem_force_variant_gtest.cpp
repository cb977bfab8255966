// The force variants: their text form, the rules between parts, and what each guarantees:
// ordered is bit-identical for any thread count and update/walls placement; per-thread and
// atomic are bit-identical to it on one thread and within round-off of it on several.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "contactlab/dem/engine.hpp"
#include "contactlab/dem/force_variant.hpp"
#include "contactlab/kernels/error.hpp"
#include "dem_support.hpp"

namespace contactlab::dem {
namespace {

TEST(DemForceVariant, EveryEnumeratedVariantRoundTrips) {
  const std::vector<ForceVariant> variants = force_variants({1, 16});
  EXPECT_GE(variants.size(), 20u);
  for (const ForceVariant& v : variants) {
    EXPECT_FALSE(broken_rule(v).has_value()) << to_string(v);
    EXPECT_EQ(parse_force_variant(to_string(v)), v) << to_string(v);
  }
  EXPECT_EQ(to_string(ForceVariant{}), "ordered/static");
  const ForceVariant report =
      parse_force_variant("per-thread/dynamic,1/walls=serial/update=separate");
  EXPECT_EQ(report.accumulation, Accumulation::kPerThread);
  EXPECT_TRUE(report.serial_walls);
  EXPECT_FALSE(report.fused_update);
  EXPECT_FALSE(thread_count_invariant(report));
  EXPECT_TRUE(thread_count_invariant(ForceVariant{}));
}

TEST(DemForceVariant, BadTextAndBrokenRulesAreInputErrors) {
  auto message = [](const std::string& text) {
    try {
      parse_force_variant(text);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_NE(message("ordered").find("ACCUMULATION/SCHEDULE"), std::string::npos);
  EXPECT_NE(message("sorted/static").find("accumulation 'sorted'"), std::string::npos);
  EXPECT_NE(message("atomic/sometimes").find("schedule"), std::string::npos);
  EXPECT_NE(message("atomic/static/walls=maybe").find("walls=maybe"), std::string::npos);
  EXPECT_NE(message("ordered/dynamic,4").find("static block partition"), std::string::npos);
  EXPECT_NE(message("atomic/static/walls=serial/update=fused").find("cannot be fused"),
            std::string::npos);
  // Per-thread and atomic sums are complete only after every pair: nothing to fuse into.
  EXPECT_NE(message("per-thread/dynamic,4/update=fused").find("needs ordered or full-list"),
            std::string::npos);
  EXPECT_NE(message("atomic/static/update=fused").find("needs ordered or full-list"),
            std::string::npos);
  EXPECT_EQ(message("full-list/dynamic,4/update=fused"), "accepted");
}

std::vector<double> run_variant(const ForceVariant& variant, int threads, int steps) {
  auto [settings, particles] = test::small_bed();
  settings.force_variant = variant;
  settings.threads = threads;
  Engine engine(settings, particles);
  engine.run_steps(static_cast<std::uint64_t>(steps));
  return test::state_by_id(engine);
}

TEST(DemForceVariant, OrderedIsBitIdenticalWhereverWallsAndUpdateRun) {
  const std::vector<double> reference = run_variant(ForceVariant{}, 1, 600);
  for (const char* text : {"ordered/static/update=fused", "ordered/static/walls=serial"}) {
    for (const int threads : {1, 3}) {
      EXPECT_TRUE(
          test::bitwise_equal(reference, run_variant(parse_force_variant(text), threads, 600)))
          << text << " at " << threads << " threads";
    }
  }
}

// The full list computes each pair once per side and sums a particle's outputs in the ordered
// pass's order with the same arithmetic: the same bits, whatever the schedule, thread count,
// update or walls placement, also with rolling resistance and through neighbour-list rebuilds.
TEST(DemForceVariant, FullListIsBitIdenticalToOrderedForAnyScheduleAndThreadCount) {
  const std::vector<double> reference = run_variant(ForceVariant{}, 1, 600);
  for (const char* text : {"full-list/static", "full-list/dynamic,1",
                           "full-list/guided,2/update=fused", "full-list/static,3/walls=serial"}) {
    EXPECT_TRUE(thread_count_invariant(parse_force_variant(text))) << text;
    for (const int threads : {1, 3}) {
      EXPECT_TRUE(
          test::bitwise_equal(reference, run_variant(parse_force_variant(text), threads, 600)))
          << text << " at " << threads << " threads";
    }
  }
  auto rolling = [](const char* text, int threads) {
    auto [settings, particles] = test::small_bed();
    settings.law.rolling_friction = 0.05;
    settings.force_variant = parse_force_variant(text);
    settings.threads = threads;
    Engine engine(settings, particles);
    engine.run_steps(400);
    EXPECT_GT(engine.rebuilds(), 1u);
    return test::state_by_id(engine);
  };
  EXPECT_TRUE(test::bitwise_equal(rolling("ordered/static", 1), rolling("full-list/dynamic,2", 2)));
}

TEST(DemForceVariant, SharedAccumulationsMatchOrderedOnOneThreadAndStayCloseOnSeveral) {
  const std::vector<double> reference = run_variant(ForceVariant{}, 1, 600);
  for (const char* text : {"per-thread/static", "per-thread/dynamic,4", "atomic/guided,2",
                           "per-thread/dynamic,1/walls=serial"}) {
    const ForceVariant variant = parse_force_variant(text);
    // One thread, rows in order: the same sums in the same order as ordered.
    if (variant.schedule.kind == ScheduleKind::kStatic) {
      EXPECT_TRUE(test::bitwise_equal(reference, run_variant(variant, 1, 600))) << text;
    }
    // Several threads: the j sides meet in another order (round-off), nothing more.
    const std::vector<double> state = run_variant(variant, 3, 600);
    ASSERT_EQ(state.size(), reference.size());
    double worst = 0.0;
    for (std::size_t k = 0; k < state.size(); ++k) {
      worst = std::max(worst,
                       std::abs(state[k] - reference[k]) / std::max(1.0, std::abs(reference[k])));
    }
    EXPECT_LT(worst, 1e-9) << text;
  }
}

}  // namespace
}  // namespace contactlab::dem
