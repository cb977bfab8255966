// Google Benchmark of every contact-detection variant, registered from the variant registry,
// on the clustered paper scene (N = 1,024,000, D = 1/200 unless CONTACTLAB_BENCH_N says
// otherwise; CTest runs it at a tiny N as a smoke test).
//
// Time per iteration = T_ALL (T_s + T_c, manual time); counters give both parts, the rates and
// the peak resident bytes per particle (peak_rss_per_particle).
#include <benchmark/benchmark.h>
#include <malloc.h>
#include <omp.h>
#include <sys/resource.h>

#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <string>

#include "contactlab/kernels/detector.hpp"
#include "contactlab/kernels/simd.hpp"
#include "paper_scene.hpp"

namespace cl = contactlab;
using contactlab::benchmarks::paper_scene;

namespace {

// Peak resident memory of the process while one benchmark runs: VmHWM of /proc/self/status,
// reset at the benchmark's start by writing "5" to /proc/self/clear_refs (Linux >= 4.0).
// getrusage's ru_maxrss cannot be reset, so in a process running every variant one after the
// other it would report the largest peak so far, not this variant's; it is the fallback where
// the reset is refused (and then an upper bound). Heap freed by earlier benchmarks is handed
// back first (malloc_trim), so their buffers are not counted as resident. The peak includes
// the scene (24 bytes per particle) and the program itself, as a user's process would.
bool reset_peak_rss() {
  malloc_trim(0);
  std::ofstream clear("/proc/self/clear_refs");
  clear << "5";
  clear.flush();
  return static_cast<bool>(clear);
}

std::uint64_t peak_rss_bytes(bool was_reset) {
  if (was_reset) {
    std::ifstream status("/proc/self/status");
    std::string field;
    while (status >> field) {
      if (field == "VmHWM:") {
        std::uint64_t kib = 0;
        status >> kib;
        return kib * 1024;
      }
    }
  }
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<std::uint64_t>(usage.ru_maxrss) * 1024;  // KiB on Linux
}

void detect_variant(benchmark::State& state, cl::Variant variant) {
  const cl::Scene& scene = paper_scene();
  const bool was_reset = reset_peak_rss();
  cl::ContactDetector detector;
  const cl::DetectOptions options{variant, cl::benchmarks::kPaperDiameter,
                                  static_cast<int>(state.range(0)), nullptr};
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
  state.counters["peak_rss_per_particle"] =
      static_cast<double>(peak_rss_bytes(was_reset)) / static_cast<double>(scene.size());
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
  benchmark::AddCustomContext("peak_rss_per_particle",
                              reset_peak_rss() ? "VmHWM, reset per benchmark (bytes / particle)"
                                               : "ru_maxrss since start (bytes / particle)");
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
