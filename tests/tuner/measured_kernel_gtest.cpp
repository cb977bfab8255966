// The detection kernel as the tuner sees it: the output it estimates from a sample of homes
// (entries against the true count, the degree rising with the clustering), the assembly phase
// inside T_c, and no estimate for one MPI rank's part.
#include <gtest/gtest.h>

#include <cstdint>
#include <tuple>
#include <vector>

#include "contactlab/kernels/scene_generate.hpp"
#include "contactlab/tuner/measured_kernel.hpp"

namespace contactlab::tuner {
namespace {

Scene make(SceneKind kind, std::uint64_t n, double diameter) {
  SceneSpec spec;
  spec.kind = kind;
  spec.n = n;
  spec.diameter = diameter;
  return generate_scene(spec);
}

// Two entries per contact: the rows of both particles.
std::uint64_t true_entries(DetectionKernel& kernel) {
  const KernelRun r = kernel.run(parse_variant("particle/sorted/half/static"), 1);
  for (const auto& [name, count] : r.counts) {
    if (name == "contact_pairs") return 2 * count;
  }
  return 0;
}

TEST(DetectionKernel, EstimatesTheOutputFromASampleOfHomes) {
  // The dense core (a few cells hold most contacts), the paper's clustering, uniform.
  std::vector<double> degrees;
  for (const auto& [kind, n, d] :
       {std::tuple{SceneKind::kCore, 60'000, 0.02}, std::tuple{SceneKind::kClustered, 60'000, 0.01},
        std::tuple{SceneKind::kUniform, 60'000, 0.03}}) {
    const Scene scene = make(kind, n, d);
    DetectionKernel kernel(scene, d);
    const double want = static_cast<double>(true_entries(kernel));
    ASSERT_GT(want, 0.0);
    const OutputEstimate got = kernel.estimated_output();
    const double entries = static_cast<double>(got.entries);
    EXPECT_NEAR(entries / want, 1.0, 0.05) << to_string(kind) << ": " << entries << " vs " << want;
    // The entry-weighted degree is at least the mean degree (equal only if all are equal).
    EXPECT_GE(got.degree, 0.95 * want / n) << to_string(kind);
    degrees.push_back(got.degree);
  }
  // The core's typical entry belongs to a far denser neighbourhood than the uniform scene's.
  EXPECT_GT(degrees[0], 3.0 * degrees[2]);
}

TEST(DetectionKernel, CountsASmallSceneWhole) {
  const Scene scene = make(SceneKind::kUniform, 200, 0.2);
  DetectionKernel kernel(scene, 0.2);
  EXPECT_EQ(kernel.estimated_output().entries, true_entries(kernel));
}

TEST(DetectionKernel, TheAssemblyIsPartOfTheDetection) {
  const Scene scene = make(SceneKind::kClustered, 20'000, 0.01);
  DetectionKernel kernel(scene, 0.01);
  for (const char* v : {"particle/sorted/half/static", "cell/sorted/full/dynamic,64"}) {
    const KernelRun r = kernel.run(parse_variant(v), 2);
    EXPECT_GE(r.phase_s("assembly"), 0.0) << v;
    EXPECT_LE(r.phase_s("assembly"), r.phase_s("detect")) << v;
  }
}

TEST(DetectionKernel, OneRanksPartEstimatesNoOutput) {
  const Scene scene = make(SceneKind::kClustered, 20'000, 0.01);
  DetectOptions part;
  part.blocks = HomeBlocks{64, 4, 1};
  DetectionKernel kernel(scene, 0.01, part);
  EXPECT_EQ(kernel.estimated_output().entries, 0u);
}

}  // namespace
}  // namespace contactlab::tuner
