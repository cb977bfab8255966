// Every variant (loop x order x stencil x schedule x precision x grid index: every_variant(),
// the hashed index with two of the schedules) on
// every scene kind with 1, 2 and 3 threads must reproduce the O(N^2) brute force exactly, and
// report the same pair and candidate counts: brute_force_contacts, float variants included
// (they decide the pairs within float rounding of touching in double).
//
// One test per (scene kind, loop, order, stencil, precision); each runs the 10 schedules x 3
// thread counts on the dense index, and 2 schedules x 3 thread counts on the hashed one.
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <map>
#include <string>
#include <tuple>

#include "contactlab/kernels/error.hpp"
#include "contactlab/kernels/simd.hpp"
#include "test_support.hpp"

namespace contactlab::test {
namespace {

struct KindSetup {
  SceneSpec spec;
  double diameter;  // detector D (ignored for polydisperse scenes)
};

// N and D chosen for a few thousand contacts and cells holding several particles each
// (max occupancy 6 to 30), while each detection stays around a millisecond.
KindSetup setup_for(SceneKind kind) {
  KindSetup setup;
  setup.spec.kind = kind;
  setup.spec.seed = 20240601;
  switch (kind) {
    case SceneKind::kUniform:
      setup.spec.n = 2000;
      setup.spec.diameter = 0.08;
      break;
    case SceneKind::kClustered:
    case SceneKind::kBlobs:
      setup.spec.n = 2500;
      setup.spec.diameter = 0.03;
      setup.spec.core = 0.5;
      setup.spec.background = 0.2;
      break;
    case SceneKind::kPolydisperse:
      setup.spec.n = 2000;
      setup.spec.diameter = 0.1;
      setup.spec.size_ratio = 4.0;
      break;
    case SceneKind::kCore:
      setup.spec.n = 2000;
      setup.spec.diameter = 0.02;
      break;
  }
  setup.diameter = setup.spec.diameter;
  return setup;
}

struct Reference {
  Scene scene;
  double diameter = 0.0;
  ContactList contacts;  // the double test's: float variants find them too
  std::uint64_t full_candidates = 0;
  TiledCandidates tiled;  // where the run shares sparse cells' ranges as tiles
};

const Reference& reference_for(SceneKind kind) {
  static std::map<SceneKind, Reference> cache;
  auto it = cache.find(kind);
  if (it == cache.end()) {
    const KindSetup setup = setup_for(kind);
    Reference ref;
    ref.scene = generate_scene(setup.spec);
    ref.diameter = setup.diameter;
    ref.contacts = brute_force_contacts(ref.scene, ref.diameter);
    ref.full_candidates = expected_full_candidates(ref.scene, ref.diameter);
    ref.tiled = expected_tiled_candidates(ref.scene, ref.diameter);
    it = cache.emplace(kind, std::move(ref)).first;
  }
  return it->second;
}

TEST(BruteForceReference, ScenesAreInterestingEnough) {
  for (const auto kind : all_scene_kinds()) {
    SCOPED_TRACE(std::string(to_string(kind)));
    const Reference& ref = reference_for(kind);
    EXPECT_TRUE(well_formed(ref.contacts));
    EXPECT_GE(ref.scene.size(), 1500u);
    EXPECT_LE(ref.scene.size(), 3000u);
    // Plenty of contacts, and cells holding several particles.
    EXPECT_GE(ref.contacts.pair_count(), 2000u);
    const Detected d = detect(ref.scene, Variant{}, ref.diameter, 1);
    EXPECT_GE(d.run.max_cell_occupancy, 6u);
    EXPECT_EQ(ref.scene.has_diameters(), kind == SceneKind::kPolydisperse);
  }
}

using Params = std::tuple<SceneKind, LoopKind, Order, Stencil, Precision>;

class EveryVariantMatchesBruteForce : public ::testing::TestWithParam<Params> {};

TEST_P(EveryVariantMatchesBruteForce, AllSchedulesAndThreadCounts) {
  const auto [kind, loop, order, stencil, precision] = GetParam();
  const Reference& ref = reference_for(kind);
  const ContactList& expected = ref.contacts;
  const std::uint64_t expected_candidates =
      stencil == Stencil::kFull ? ref.full_candidates : ref.full_candidates / 2;
  const std::uint64_t expected_tiled = stencil == Stencil::kFull ? ref.tiled.full : ref.tiled.half;
  const CellGrid grid(ref.scene.box,
                      ref.scene.has_diameters() ? ref.scene.max_diameter() : ref.diameter,
                      CellNumbering::kLinear);

  int runs = 0;
  for (const Variant& variant : every_variant()) {
    if (variant.loop != loop || variant.order != order || variant.stencil != stencil ||
        variant.precision != precision) {
      continue;
    }
    for (const int threads : {1, 2, 3}) {
      SCOPED_TRACE(to_string(variant) + " threads=" + std::to_string(threads));
      const Detected d = detect(ref.scene, variant, ref.diameter, threads);
      ++runs;
      EXPECT_TRUE(same_contacts(d.contacts, expected));
      EXPECT_EQ(d.run.contact_pairs, expected.pair_count());
      // The same for every schedule and thread count, and without tiles (full) twice the half
      // stencil's.
      EXPECT_EQ(d.run.candidate_tests, d.run.tiled ? expected_tiled : expected_candidates);
      // Tiles: the particle loop over particles in linear cell order, tested on SIMD lanes.
      EXPECT_TRUE(!d.run.tiled ||
                  (loop == LoopKind::kParticle && order == Order::kSorted && simd_enabled()));
      EXPECT_EQ(d.run.threads, threads);
      EXPECT_EQ(d.run.thread_busy_s.size(), static_cast<std::size_t>(threads));
      EXPECT_EQ(d.run.grid_dims, grid.dims());
    }
  }
  EXPECT_EQ(runs, 39);  // (10 dense + balanced + 2 hashed schedules) x 3 thread counts
}

std::string param_name(const ::testing::TestParamInfo<Params>& info) {
  const auto [kind, loop, order, stencil, precision] = info.param;
  return std::string(to_string(kind)) + "_" + std::string(to_string(loop)) + "_" +
         std::string(to_string(order)) + "_" + std::string(to_string(stencil)) + "_" +
         std::string(to_string(precision));
}

INSTANTIATE_TEST_SUITE_P(
    Kernels, EveryVariantMatchesBruteForce,
    ::testing::Combine(::testing::Values(SceneKind::kUniform, SceneKind::kClustered,
                                         SceneKind::kBlobs, SceneKind::kPolydisperse,
                                         SceneKind::kCore),
                       ::testing::Values(LoopKind::kCell, LoopKind::kParticle),
                       ::testing::Values(Order::kUnsorted, Order::kSorted, Order::kMorton),
                       ::testing::Values(Stencil::kFull, Stencil::kHalf),
                       ::testing::Values(Precision::kDouble, Precision::kFloat)),
    param_name);

// The sorted layouts' contact tests on every SIMD target this CPU runs and this build holds
// (AVX3_DL and AVX3 = AVX-512, AVX2, SSE4, SSSE3, EMU128 or SCALAR) and on the scalar loop ("off"):
// every scene kind, loop, sorted order, stencil and precision, two schedules, 1 and 3 threads,
// against the brute force. (The suite above runs the default target with every schedule.)
class SortedVariantsMatchBruteForce : public ::testing::TestWithParam<std::string> {};

TEST_P(SortedVariantsMatchBruteForce, OnThisSimdTarget) {
  select_simd_target(GetParam());
  EXPECT_EQ(simd_target(), GetParam() == "best" ? simd_targets().front() : GetParam());
  int runs = 0;
  for (const auto kind : all_scene_kinds()) {
    const Reference& ref = reference_for(kind);
    for (const Variant& variant : every_variant()) {
      const Schedule& schedule = variant.schedule;
      const bool picked = (schedule.kind == ScheduleKind::kStatic && schedule.chunk == 0) ||
                          (schedule.kind == ScheduleKind::kDynamic && schedule.chunk == 7);
      if (variant.order == Order::kUnsorted || !picked) continue;
      const ContactList& expected = ref.contacts;
      for (const int threads : {1, 3}) {
        SCOPED_TRACE(std::string(to_string(kind)) + " " + to_string(variant) +
                     " threads=" + std::to_string(threads));
        const Detected d = detect(ref.scene, variant, ref.diameter, threads);
        ++runs;
        EXPECT_TRUE(same_contacts(d.contacts, expected));
        EXPECT_EQ(d.run.contact_pairs, expected.pair_count());
      }
    }
  }
  // kinds, loops, orders, stencils, precisions, grid indexes, schedules, thread counts
  EXPECT_EQ(runs, 5 * 2 * 2 * 2 * 2 * 2 * 2 * 2);
  select_simd_target("best");
}

INSTANTIATE_TEST_SUITE_P(Kernels, SortedVariantsMatchBruteForce,
                         ::testing::ValuesIn(simd_targets()),
                         [](const ::testing::TestParamInfo<std::string>& target) {
                           return target.param;
                         });

TEST(SimdTarget, ListsTheScalarLoopAndRefusesUnknownNames) {
  const std::vector<std::string> targets = simd_targets();
  ASSERT_GE(targets.size(), 2u);
  EXPECT_EQ(targets.back(), "off");
  // Highway's portable path (EMU128, or SCALAR where its emulation is broken) is always built.
  const std::string& portable = targets[targets.size() - 2];
  EXPECT_TRUE(portable == "EMU128" || portable == "SCALAR") << portable;
  try {
    select_simd_target("avx9000");
    FAIL() << "an unknown target was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("avx9000"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find(portable), std::string::npos);
  }
  select_simd_target("off");
  EXPECT_EQ(simd_target(), "off");
  EXPECT_FALSE(simd_enabled());
  std::string lower = portable;
  for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  select_simd_target(lower);  // case-insensitive
  EXPECT_EQ(simd_target(), portable);
  select_simd_target("best");
  EXPECT_EQ(simd_target(), targets.front());
}

// The candidate count does not depend on the loop or the order either, and the full stencil
// makes exactly twice the half stencil's tests (each unordered pair once from each side); with
// tiles (the particle loop in cell order on SIMD lanes) the tiles' counts.
TEST(CandidateTests, FullIsTwiceHalfForEveryLoopAndOrder) {
  const Reference& ref = reference_for(SceneKind::kBlobs);
  ASSERT_EQ(ref.full_candidates % 2, 0u);
  for (const auto precision : {Precision::kDouble, Precision::kFloat}) {
    for (const auto loop : {LoopKind::kCell, LoopKind::kParticle}) {
      for (const auto order : {Order::kUnsorted, Order::kSorted, Order::kMorton}) {
        const Schedule schedule{ScheduleKind::kStatic, 0};
        const Detected full = detect(
            ref.scene, Variant{loop, order, Stencil::kFull, schedule, precision}, ref.diameter, 1);
        const Detected half = detect(
            ref.scene, Variant{loop, order, Stencil::kHalf, schedule, precision}, ref.diameter, 1);
        SCOPED_TRACE(std::string(to_string(loop)) + "/" + std::string(to_string(order)) + "/" +
                     std::string(to_string(precision)));
        EXPECT_EQ(full.run.tiled, half.run.tiled);
        if (full.run.tiled) {
          EXPECT_EQ(full.run.candidate_tests, ref.tiled.full);
          EXPECT_EQ(half.run.candidate_tests, ref.tiled.half);
          continue;
        }
        EXPECT_EQ(full.run.candidate_tests, 2 * half.run.candidate_tests);
        EXPECT_EQ(full.run.candidate_tests, ref.full_candidates);
      }
    }
  }
}

// The brute force itself, on a case small enough to check by hand.
TEST(BruteForceReference, HandCheckedTriangle) {
  // 0-1 at distance 1 (touching, D = 1), 1-2 at distance 0.5, 0-2 at distance 1.5.
  const Scene scene =
      make_scene({{0.0, 0.0, 0.0}, {1.0, 0.0, 0.0}, {1.5, 0.0, 0.0}}, Box{{0, 0, 0}, {2, 2, 2}});
  const ContactList got = brute_force_contacts(scene, 1.0);
  EXPECT_TRUE(same_contacts(got, list_from_pairs(3, {{0, 1}, {1, 2}})));
  // Per-particle diameters: (d0 + d2) / 2 = 1.5 just reaches particle 2, (d1 + d2) / 2 = 1.25
  // reaches it too, (d0 + d1) / 2 = 0.75 < 1 does not reach; the scalar D is ignored.
  Scene poly = scene;
  poly.diameter = {1.0, 0.5, 2.0};
  EXPECT_TRUE(
      same_contacts(brute_force_contacts(poly, 123.0), list_from_pairs(3, {{0, 2}, {1, 2}})));
}

}  // namespace
}  // namespace contactlab::test
