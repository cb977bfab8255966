// The step's instruction sets (engine_isa.cpp): each set this CPU runs gives the same bits as
// every other, for every force accumulation, with rolling resistance and the clamp; the engine
// follows the detection's process-wide choice (simd.hpp) and says which set it ran; the
// validation cases give the same numbers on each.
#include <gtest/gtest.h>

#include <set>
#include <string>
#include <vector>

#include "contactlab/dem/engine.hpp"
#include "contactlab/dem/force_variant.hpp"
#include "contactlab/dem/validation.hpp"
#include "contactlab/kernels/simd.hpp"
#include "dem_support.hpp"

namespace contactlab::dem {
namespace {

// One Highway target per step instruction set this CPU runs (the first, the best, of each).
std::vector<std::string> one_target_per_set() {
  std::vector<std::string> targets;
  std::set<StepIsa> seen;
  for (const std::string& t : simd_targets()) {
    select_simd_target(t);
    if (seen.insert(step_isa()).second) targets.push_back(t);
  }
  select_simd_target("best");
  return targets;
}

// Restores the best target however a test ends.
struct BestTargetAfter {
  ~BestTargetAfter() { select_simd_target("best"); }
};

TEST(DemStepIsa, FollowsTheDetectionsChoice) {
  const BestTargetAfter restore;
  for (const std::string& t : simd_targets()) {
    select_simd_target(t);
    const StepIsa expected = t.starts_with("AVX3") ? StepIsa::kAvx512
                             : t == "AVX2"         ? StepIsa::kAvx2
                                                   : StepIsa::kBaseline;
#if defined(__x86_64__)
    EXPECT_EQ(step_isa(), expected) << t;
#else
    EXPECT_EQ(step_isa(), StepIsa::kBaseline) << t;
#endif
    auto [settings, particles] = test::small_bed(40);
    const Engine engine(settings, particles);
    EXPECT_EQ(engine.instruction_set(), step_isa()) << t;
  }
  EXPECT_EQ(to_string(StepIsa::kAvx512), "AVX-512");
  EXPECT_EQ(to_string(StepIsa::kAvx2), "AVX2");
  EXPECT_EQ(to_string(StepIsa::kBaseline), "baseline");
}

// Every set on the bed (walls, periodic pairs, rebuilds), for each accumulation and with the
// rolling law and the tangential clamp on, at one and three threads: the same state, bit for
// bit, as the first set's.
TEST(DemStepIsa, EverySetGivesTheSameBits) {
  const BestTargetAfter restore;
  const std::vector<std::string> targets = one_target_per_set();
  if (targets.size() < 2) GTEST_SKIP() << "this CPU runs one step instruction set only";
  for (const char* variant : {"ordered/static", "ordered/static/update=fused", "full-list/static",
                              "per-thread/dynamic,16", "atomic/dynamic,16"}) {
    for (const bool rolling_unclamped : {false, true}) {
      const double rolling = rolling_unclamped ? 0.1 : 0.0;
      std::vector<double> reference;
      for (const std::string& t : targets) {
        for (const int threads : {1, 3}) {
          select_simd_target(t);
          auto [settings, particles] = test::small_bed();
          settings.law.rolling_friction = rolling;
          settings.law.clamp_normal_force = !rolling_unclamped;
          settings.force_variant = parse_force_variant(variant);
          settings.threads = threads;
          Engine engine(settings, particles);
          engine.run_steps(600);
          const std::vector<double> state = test::state_by_id(engine);
          if (reference.empty()) {
            reference = state;
          } else if (threads == 1 || thread_count_invariant(settings.force_variant)) {
            EXPECT_TRUE(test::bitwise_equal(reference, state))
                << variant << ", rolling " << rolling << ", " << t << ", " << threads << " threads";
          }
        }
      }
    }
  }
}

// `dem validate`'s numbers on every set: each row's measured value, bit for bit.
TEST(DemStepIsa, ValidationCasesGiveTheSameNumbersOnEverySet) {
  const BestTargetAfter restore;
  const std::vector<std::string> targets = one_target_per_set();
  if (targets.size() < 2) GTEST_SKIP() << "this CPU runs one step instruction set only";
  std::vector<double> reference;
  for (const std::string& t : targets) {
    select_simd_target(t);
    std::vector<double> measured;
    for (const ValidationCase& c : validation_cases()) {
      for (const ValidationRow& r : c.run()) {
        EXPECT_TRUE(r.pass) << c.name << " " << r.quantity << " on " << t;
        measured.push_back(r.measured);
      }
    }
    if (reference.empty()) {
      reference = measured;
    } else {
      EXPECT_TRUE(test::bitwise_equal(reference, measured)) << t;
    }
  }
}

}  // namespace
}  // namespace contactlab::dem
