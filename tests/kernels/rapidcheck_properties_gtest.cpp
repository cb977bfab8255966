// Randomised properties (rapidcheck) with fixed seeds: random small scenes, random variants and
// thread counts must match the brute force; variant strings round-trip.
//
// Seeds are fixed here (not taken from RC_PARAMS or the clock) so that every run checks the same
// cases; a failure prints the shrunk counterexample.
#include <gtest/gtest.h>
#include <rapidcheck.h>
#include <rapidcheck/gtest.h>

#include <sstream>

#include "rapidcheck_seeded.hpp"
#include "test_support.hpp"

namespace contactlab::test {
namespace {

const std::vector<Variant>& all() {
  static const std::vector<Variant> variants = every_variant();
  return variants;
}

// Runs `variant` and returns a description of the first disagreement with the brute force
// (float variants too: they decide near-ties in double), or an empty string.
std::string disagreement(const Scene& scene, double d, const Variant& variant, int threads) {
  const ContactList expected = brute_force_contacts(scene, d);
  const Detected got = detect(scene, variant, d, threads);
  std::ostringstream out;
  const auto same = same_contacts(got.contacts, expected);
  if (!same) out << same.message();
  if (got.run.contact_pairs != expected.pair_count())
    out << " contact_pairs " << got.run.contact_pairs;
  const std::uint64_t full = expected_full_candidates(scene, d);
  std::uint64_t want = variant.stencil == Stencil::kFull ? full : full / 2;
  if (got.run.tiled) {
    const TiledCandidates tiled = expected_tiled_candidates(scene, d);
    want = variant.stencil == Stencil::kFull ? tiled.full : tiled.half;
  }
  if (got.run.candidate_tests != want)
    out << " candidate_tests " << got.run.candidate_tests << " != " << want;
  return out.str();
}

// Generated scenes of every kind: N up to 300, D from 0.02 to 0.6, random seed and box.
TEST(RapidCheck, GeneratedScenesMatchBruteForce) {
  check_with_seed(0x5eed0001, 150, [] {
    SceneSpec spec;
    spec.kind = *rc::gen::elementOf(all_scene_kinds());
    spec.n = static_cast<std::uint64_t>(*rc::gen::inRange(0, 301));
    spec.seed = *rc::gen::arbitrary<std::uint64_t>();
    spec.core = *rc::gen::elementOf(std::vector<double>{0.02, 0.2, 1.0});
    spec.background = *rc::gen::elementOf(std::vector<double>{0.0, 0.5});
    spec.size_ratio = *rc::gen::elementOf(std::vector<double>{1.0, 3.0, 20.0});
    const double scale = *rc::gen::elementOf(std::vector<double>{1.0, 0.5, 3.0});
    const double offset = *rc::gen::elementOf(std::vector<double>{0.0, -2.0, 1000.0});
    spec.box = Box{{offset, offset, offset}, {offset + scale, offset + 2 * scale, offset + scale}};
    spec.diameter = scale * *rc::gen::inRange(2, 61) / 100.0;
    const Scene scene = generate_scene(spec);
    const Variant variant = *rc::gen::elementOf(all());
    const int threads = *rc::gen::inRange(1, 4);
    RC_TAG(std::string(to_string(spec.kind)));
    const std::string problem = disagreement(scene, spec.diameter, variant, threads);
    RC_ASSERT(problem == std::string());
  });
}

// Points on a coarse dyadic grid (multiples of 1/16) with D a multiple of 1/16: exact ties at
// distance D, D sqrt 2, ..., coincident points and points on the upper faces are everywhere.
// Half of the cases use per-particle diameters (multiples of 1/32).
TEST(RapidCheck, TiesOnADyadicGridMatchBruteForce) {
  check_with_seed(0x5eed0002, 200, [] {
    const int n = *rc::gen::inRange(0, 250);
    const int steps = *rc::gen::elementOf(std::vector<int>{4, 16});
    const bool per_particle = *rc::gen::arbitrary<bool>();
    Scene scene;
    for (int i = 0; i < n; ++i) {
      scene.x.push_back(*rc::gen::inRange(0, steps + 1) / double(steps));
      scene.y.push_back(*rc::gen::inRange(0, steps + 1) / double(steps));
      scene.z.push_back(*rc::gen::inRange(0, steps + 1) / double(steps));
      if (per_particle) scene.diameter.push_back(*rc::gen::inRange(1, 9) / 32.0);
    }
    const double d = *rc::gen::inRange(1, 9) / 16.0;
    const Variant variant = *rc::gen::elementOf(all());
    const int threads = *rc::gen::inRange(1, 4);
    const std::string problem = disagreement(scene, d, variant, threads);
    RC_ASSERT(problem == std::string());
  });
}

// Random points in the unit box (not from the generators), every variant on each draw.
TEST(RapidCheck, EveryVariantAgreesOnRandomPoints) {
  check_with_seed(0x5eed0003, 25, [] {
    const auto points = *rc::gen::container<std::vector<std::array<double, 3>>>(rc::gen::apply(
        [](int a, int b, int c) {
          return std::array<double, 3>{a / 1e6, b / 1e6, c / 1e6};
        },
        rc::gen::inRange(0, 1000001), rc::gen::inRange(0, 1000001), rc::gen::inRange(0, 1000001)));
    const Scene scene = make_scene(points);
    const double d = *rc::gen::inRange(1, 40) / 100.0;
    const ContactList expected = brute_force_contacts(scene, d);
    for (const Variant& v : all()) {
      const Detected got = detect(scene, v, d, 2);
      RC_ASSERT(got.contacts == expected);
    }
  });
}

// A random permutation of the input permutes the contacts and nothing else.
TEST(RapidCheck, PermutationInvariance) {
  check_with_seed(0x5eed0004, 60, [] {
    SceneSpec spec;
    spec.kind = *rc::gen::elementOf(all_scene_kinds());
    spec.n = static_cast<std::uint64_t>(*rc::gen::inRange(0, 400));
    spec.seed = *rc::gen::arbitrary<std::uint64_t>();
    spec.core = 0.3;
    spec.diameter = *rc::gen::inRange(2, 30) / 100.0;
    const Scene scene = generate_scene(spec);
    const auto perm = permutation(scene.size(), *rc::gen::arbitrary<std::uint64_t>());
    Scene shuffled;
    for (const std::uint32_t i : perm) {
      shuffled.x.push_back(scene.x[i]);
      shuffled.y.push_back(scene.y[i]);
      shuffled.z.push_back(scene.z[i]);
      if (scene.has_diameters()) shuffled.diameter.push_back(scene.diameter[i]);
    }
    const Variant variant = *rc::gen::elementOf(all());
    const Detected original = detect(scene, variant, spec.diameter, 1);
    const Detected moved = detect(shuffled, variant, spec.diameter, *rc::gen::inRange(1, 4));
    std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
    for (std::size_t k = 0; k < moved.contacts.particle_count(); ++k) {
      for (const std::uint32_t l : moved.contacts.partners_of(k))
        pairs.emplace_back(perm[k], perm[l]);
    }
    std::vector<std::pair<std::uint32_t, std::uint32_t>> halves;
    for (const auto& [a, b] : pairs) {
      if (a < b) halves.emplace_back(a, b);
    }
    RC_ASSERT(list_from_pairs(scene.size(), halves) == original.contacts);
    RC_ASSERT(moved.run.candidate_tests == original.run.candidate_tests);
  });
}

// Any variant (any chunk) prints to a string that parses back to it.
TEST(RapidCheck, VariantStringsRoundTrip) {
  check_with_seed(0x5eed0005, 300, [] {
    Variant v;
    v.loop = *rc::gen::element(LoopKind::kCell, LoopKind::kParticle);
    v.order = *rc::gen::element(Order::kUnsorted, Order::kSorted, Order::kMorton);
    v.stencil = *rc::gen::element(Stencil::kFull, Stencil::kHalf);
    v.schedule.kind =
        *rc::gen::element(ScheduleKind::kStatic, ScheduleKind::kDynamic, ScheduleKind::kGuided);
    v.schedule.chunk =
        *rc::gen::inRange(v.schedule.kind == ScheduleKind::kStatic ? 0 : 1, 1000000001);
    v.precision = *rc::gen::element(Precision::kDouble, Precision::kFloat);
    const std::string text = to_string(v);
    RC_ASSERT(parse_variant(text) == v);
    // Three-part form of a full-stencil double variant.
    if (v.stencil == Stencil::kFull && v.precision == Precision::kDouble) {
      const std::string three = std::string(to_string(v.loop)) + "/" +
                                std::string(to_string(v.order)) + "/" + to_string(v.schedule);
      RC_ASSERT(parse_variant(three) == v);
    }
  });
}

}  // namespace
}  // namespace contactlab::test
