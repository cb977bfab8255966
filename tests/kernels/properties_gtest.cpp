// Invariants of contact detection over generated scenes: symmetric partner lists, invariance
// under permutation of the input, independence of threads and schedule, determinism, and
// monotonicity in D.
#include <gtest/gtest.h>

#include <map>

#include "test_support.hpp"

namespace contactlab::test {
namespace {

Scene scene_of(SceneKind kind, std::uint64_t n, double d, std::uint64_t seed) {
  SceneSpec spec;
  spec.kind = kind;
  spec.n = n;
  spec.diameter = d;
  spec.seed = seed;
  spec.core = 0.3;
  spec.background = 0.1;
  return generate_scene(spec);
}

Scene permuted(const Scene& scene, const std::vector<std::uint32_t>& perm) {
  // Row k of the permuted scene is row perm[k] of the original.
  Scene out;
  out.box = scene.box;
  for (const std::uint32_t i : perm) {
    out.x.push_back(scene.x[i]);
    out.y.push_back(scene.y[i]);
    out.z.push_back(scene.z[i]);
    if (scene.has_diameters()) out.diameter.push_back(scene.diameter[i]);
  }
  return out;
}

// Contacts of the permuted scene, renamed back to the original rows.
ContactList map_back(const ContactList& list, const std::vector<std::uint32_t>& perm) {
  std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
  for (std::size_t k = 0; k < list.particle_count(); ++k) {
    for (const std::uint32_t l : list.partners_of(k)) {
      if (k < l) pairs.emplace_back(perm[k], perm[l]);
    }
  }
  return list_from_pairs(list.particle_count(), pairs);
}

TEST(Property, PartnerListsAreSymmetricWithoutSelfContacts) {
  for (const auto kind : all_scene_kinds()) {
    const Scene scene = scene_of(kind, 3000, 0.04, 101);
    for (const Variant& v : covering_variants()) {
      for (const int threads : {1, 3}) {
        SCOPED_TRACE(std::string(to_string(kind)) + " " + to_string(v) +
                     " threads=" + std::to_string(threads));
        ContactDetector detector;
        DetectOptions options;
        options.variant = v;
        options.diameter = 0.04;
        options.threads = threads;
        detector.run(scene, options);
        EXPECT_TRUE(well_formed(detector.canonical_contacts()));
        // The raw (working-id) list is symmetric too, before canonicalization: each contact
        // sits in both partners' rows, so the sum of counts is twice the pair count.
        const ContactList& raw = detector.contacts();
        EXPECT_EQ(raw.particle_count(), scene.size());
        EXPECT_EQ(raw.partners.size() % 2, 0u);
        std::uint64_t sum = 0;
        for (std::size_t i = 0; i < raw.particle_count(); ++i) sum += raw.count(i);
        EXPECT_EQ(sum, 2 * raw.pair_count());
      }
    }
  }
}

TEST(Property, InvariantUnderPermutationOfTheInput) {
  for (const auto kind : all_scene_kinds()) {
    const Scene scene = scene_of(kind, 2500, 0.04, 202);
    const ContactList expected = brute_force_contacts(scene, 0.04);
    for (const std::uint64_t seed : {1ULL, 2ULL}) {
      const auto perm = permutation(scene.size(), seed);
      const Scene shuffled = permuted(scene, perm);
      ASSERT_NE(scene.x, shuffled.x);
      for (const Variant& v : covering_variants()) {
        SCOPED_TRACE(std::string(to_string(kind)) + " " + to_string(v) + " permutation " +
                     std::to_string(seed));
        const Detected got = detect(shuffled, v, 0.04, 2);
        const ContactList& want = expected;
        EXPECT_TRUE(same_contacts(map_back(got.contacts, perm), want));
        EXPECT_EQ(got.run.contact_pairs, want.pair_count());
      }
    }
  }
}

// The same contacts for every schedule and thread count, on a scene larger than the
// equivalence tests use (so that dynamic and guided chunks really interleave) and with 4
// threads, more than the equivalence tests use.
TEST(Property, SameResultForEveryThreadCountAndSchedule) {
  const Scene scene = scene_of(SceneKind::kBlobs, 5000, 0.02, 303);
  std::map<Precision, Detected> reference;
  for (const auto precision : {Precision::kDouble, Precision::kFloat}) {
    reference[precision] = detect(
        scene, Variant{LoopKind::kCell, Order::kSorted, Stencil::kFull, {}, precision}, 0.02, 1);
  }
  ASSERT_GT(reference[Precision::kDouble].contacts.pair_count(), 5000u);
  ASSERT_TRUE(
      same_contacts(reference[Precision::kDouble].contacts, brute_force_contacts(scene, 0.02)));
  ASSERT_TRUE(
      same_contacts(reference[Precision::kFloat].contacts, reference[Precision::kDouble].contacts));
  const TiledCandidates tiled = expected_tiled_candidates(scene, 0.02);
  int failures = 0;
  for (const Variant& v : every_variant()) {
    const Detected& want = reference[v.precision];
    for (const int threads : {2, 4}) {
      const Detected got = detect(scene, v, 0.02, threads);
      const auto same = same_contacts(got.contacts, want.contacts);
      if (!same) {
        ADD_FAILURE() << to_string(v) << " threads=" << threads << ": " << same.message();
        if (++failures >= 5) return;
      }
      if (got.run.tiled) {  // the tiles' counts: the same for every schedule too
        EXPECT_EQ(got.run.candidate_tests, v.stencil == Stencil::kFull ? tiled.full : tiled.half);
        continue;
      }
      EXPECT_EQ(got.run.candidate_tests, v.stencil == Stencil::kFull
                                             ? want.run.candidate_tests
                                             : want.run.candidate_tests / 2);
    }
  }
}

// Running twice, with the same detector or a new one, gives the same raw lists for a
// deterministic configuration (one thread) and the same canonical lists always.
TEST(Property, RepeatedRunsAgree) {
  const Scene scene = scene_of(SceneKind::kClustered, 4000, 0.03, 404);
  for (const Variant& v : covering_variants()) {
    SCOPED_TRACE(to_string(v));
    ContactDetector detector;
    DetectOptions options;
    options.variant = v;
    options.diameter = 0.03;
    options.threads = 1;
    detector.run(scene, options);
    const ContactList raw = detector.contacts();
    const ContactList canonical = detector.canonical_contacts();
    detector.run(scene, options);
    EXPECT_EQ(detector.contacts(), raw);
    options.threads = 3;
    detector.run(scene, options);
    EXPECT_TRUE(same_contacts(detector.canonical_contacts(), canonical));
  }
}

// A larger D never loses a contact.
TEST(Property, ContactsGrowWithTheDiameter) {
  const Scene scene = scene_of(SceneKind::kUniform, 3000, 0.05, 505);
  ContactList previous = list_from_pairs(scene.size(), {});
  for (const double d : {0.01, 0.02, 0.035, 0.05, 0.08}) {
    const Detected got = detect(scene, parse_variant("particle/morton/half/guided,7"), d, 2);
    for (std::size_t i = 0; i < scene.size(); ++i) {
      const auto now = got.contacts.partners_of(i);
      const auto before = previous.partners_of(i);
      ASSERT_TRUE(std::includes(now.begin(), now.end(), before.begin(), before.end()))
          << "particle " << i << " lost a contact going to D = " << d;
    }
    EXPECT_GE(got.contacts.pair_count(), previous.pair_count());
    previous = got.contacts;
  }
  EXPECT_GT(previous.pair_count(), 1000u);
}

}  // namespace
}  // namespace contactlab::test
