// Google Benchmark of every contact-detection variant, registered from the variant registry,
// on the clustered paper scene (N = 1,024,000, D = 1/200 unless CONTACTLAB_BENCH_N says
// otherwise; CTest runs it at a tiny N as a smoke test).
//
// Time per iteration = T_ALL (T_s + T_c, manual time); counters give both parts and the rates.
#include <benchmark/benchmark.h>
#include <omp.h>

#include <cstdlib>
#include <memory>
#include <string>

#include "contactlab/kernels/detector.hpp"
#include "contactlab/kernels/scene_generate.hpp"
#include "contactlab/kernels/simd.hpp"

namespace cl = contactlab;

namespace {

const cl::Scene& paper_scene() {
  static const cl::Scene scene = [] {
    cl::SceneSpec spec;
    spec.kind = cl::SceneKind::kClustered;
    spec.n = 1'024'000;
    if (const char* n = std::getenv("CONTACTLAB_BENCH_N")) spec.n = std::strtoull(n, nullptr, 10);
    spec.diameter = 1.0 / 200.0;
    spec.seed = 1;
    return cl::generate_scene(spec);
  }();
  return scene;
}

void detect_variant(benchmark::State& state, cl::Variant variant) {
  const cl::Scene& scene = paper_scene();
  cl::ContactDetector detector;
  const cl::DetectOptions options{variant, 1.0 / 200.0, static_cast<int>(state.range(0)), nullptr};
  detector.run(scene, options);  // warm-up: buffers and pages
  double setup = 0.0, detect = 0.0;
  std::uint64_t tests = 0, contacts = 0;
  for (auto _ : state) {
    const cl::DetectRun run = detector.run(scene, options);
    state.SetIterationTime(run.total_s());
    setup += run.setup_s;
    detect += run.detect_s;
    tests = run.candidate_tests;
    contacts = run.contact_pairs;
  }
  const double iterations = static_cast<double>(state.iterations());
  state.counters["T_s"] = setup / iterations;
  state.counters["T_c"] = detect / iterations;
  state.counters["tests_per_s"] = static_cast<double>(tests) * iterations / detect;
  state.counters["contacts_per_s"] = static_cast<double>(contacts) * iterations / detect;
  state.counters["candidate_tests"] = static_cast<double>(tests);
  state.counters["contacts"] = static_cast<double>(contacts);
  state.SetLabel(std::to_string(scene.size()) + " particles");
}

}  // namespace

int main(int argc, char** argv) {
  const int cores = omp_get_num_procs();
  for (const cl::Variant& variant : cl::enumerate(cl::all_variants({200}))) {
    auto* bench = benchmark::RegisterBenchmark(("detect/" + cl::to_string(variant)).c_str(),
                                               detect_variant, variant);
    bench->Arg(1)->ArgName("threads")->UseManualTime()->Unit(benchmark::kMillisecond);
    if (cores > 1) bench->Arg(cores);
  }
  benchmark::AddCustomContext("simd_target", cl::simd_target());
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
