// The scene both kernel benchmarks run on: Takagi et al.'s clustered scene, N = 1,024,000 and
// D = 1/200 unless CONTACTLAB_BENCH_N says otherwise (CTest runs them at a tiny N as smoke
// tests), generated once per process.
#pragma once

#include <cstdlib>

#include "contactlab/kernels/scene_generate.hpp"

namespace contactlab::benchmarks {

inline constexpr double kPaperDiameter = 1.0 / 200.0;

inline const Scene& paper_scene() {
  static const Scene scene = [] {
    SceneSpec spec;
    spec.kind = SceneKind::kClustered;
    spec.n = 1'024'000;
    if (const char* n = std::getenv("CONTACTLAB_BENCH_N")) spec.n = std::strtoull(n, nullptr, 10);
    spec.diameter = kPaperDiameter;
    spec.seed = 1;
    return generate_scene(spec);
  }();
  return scene;
}

}  // namespace contactlab::benchmarks
