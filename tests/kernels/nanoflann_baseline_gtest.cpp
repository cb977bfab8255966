// The k-d tree baseline of the benchmarks (kernels/benchmark/nanoflann_baseline.hpp) finds
// exactly the detector's contacts: on clustered scenes at 1 and 2 threads and several leaf
// sizes, and on a lattice whose neighbours are exactly D apart (contact at <= D^2, where
// nanoflann keeps a point below the radius); and refuses what it cannot do.
#include <gtest/gtest.h>

#include "contactlab/kernels/detector.hpp"
#include "contactlab/kernels/error.hpp"
#include "contactlab/kernels/scene_generate.hpp"
#include "nanoflann_baseline.hpp"

namespace contactlab {
namespace {

ContactList detector_contacts(const Scene& scene, double diameter) {
  ContactDetector detector;
  detector.run(scene, {parse_variant("particle/sorted/full/static"), diameter, 1, nullptr});
  return detector.canonical_contacts();
}

TEST(NanoflannBaseline, FindsTheDetectorsContacts) {
  for (const SceneKind kind : {SceneKind::kClustered, SceneKind::kCore, SceneKind::kUniform}) {
    SceneSpec spec;
    spec.kind = kind;
    spec.n = 20'000;
    spec.diameter = 0.01;
    spec.seed = 5;
    const Scene scene = generate_scene(spec);
    const ContactList expected = detector_contacts(scene, spec.diameter);
    ASSERT_GT(expected.pair_count(), 0u);
    baseline::NanoflannContacts search;
    for (const int threads : {1, 2}) {
      for (const std::size_t leaf : {1u, 10u, 64u}) {
        const baseline::NanoflannRun run = search.run(scene, spec.diameter, threads, leaf);
        EXPECT_GE(run.build_s, 0.0);
        EXPECT_EQ(canonicalize(search.contacts(), {}), expected)
            << "threads " << threads << ", leaf " << leaf;
      }
    }
  }
}

TEST(NanoflannBaseline, KeepsNeighboursExactlyDApart) {
  // A 5 x 5 x 5 lattice of spacing 0.25 = D: every squared distance is exact, and each
  // lattice neighbour is a contact at exactly D^2.
  Scene scene;
  scene.box = {{0, 0, 0}, {1, 1, 1}};
  for (int i = 0; i < 5; ++i) {
    for (int j = 0; j < 5; ++j) {
      for (int k = 0; k < 5; ++k) {
        scene.x.push_back(0.25 * i);
        scene.y.push_back(0.25 * j);
        scene.z.push_back(0.25 * k);
      }
    }
  }
  const ContactList expected = detector_contacts(scene, 0.25);
  EXPECT_EQ(expected.pair_count(), 3u * 5 * 5 * 4);  // 4 neighbours along each row
  baseline::NanoflannContacts search;
  search.run(scene, 0.25, 2, 4);
  EXPECT_EQ(canonicalize(search.contacts(), {}), expected);
}

TEST(NanoflannBaseline, RefusesWhatOneRadiusCannotDo) {
  SceneSpec spec;
  spec.kind = SceneKind::kPolydisperse;
  spec.n = 100;
  spec.diameter = 0.05;
  const Scene polydisperse = generate_scene(spec);
  baseline::NanoflannContacts search;
  EXPECT_THROW(search.run(polydisperse, 0.05, 1, 10), InputError);
  spec.kind = SceneKind::kUniform;
  const Scene uniform = generate_scene(spec);
  EXPECT_THROW(search.run(uniform, 0.0, 1, 10), InputError);
  EXPECT_THROW(search.run(uniform, 0.05, 1, 0), InputError);
  EXPECT_THROW(search.run(uniform, 0.05, 0, 10), InputError);
}

}  // namespace
}  // namespace contactlab
