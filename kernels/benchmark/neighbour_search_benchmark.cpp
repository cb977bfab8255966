// Google Benchmark: the detector against the neighbour search a user would take off the shelf
// (nanoflann's k-d tree, nanoflann_baseline.hpp) on the clustered paper scene (N = 1,024,000,
// D = 1/200 unless CONTACTLAB_BENCH_N says otherwise), at 1 thread and all cores. Both write
// every particle's partner row. Before any timing the two contact lists are compared row by
// row (canonical form: input rows, partners ascending) and the program stops if they differ:
// a speed-up is only reported with its error, and that error is zero.
//
// Time per iteration = build + search (nanoflann) or T_s + T_c (the detector), manual time.
// One interleaved run, as the README gives it: --benchmark_repetitions=10
// --benchmark_enable_random_interleaving=true --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>
#include <omp.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>

#include "contactlab/kernels/build_info.hpp"
#include "contactlab/kernels/detector.hpp"
#include "contactlab/kernels/simd.hpp"
#include "nanoflann_baseline.hpp"
#include "paper_scene.hpp"

namespace cl = contactlab;
using contactlab::benchmarks::paper_scene;

namespace {

constexpr double kDiameter = cl::benchmarks::kPaperDiameter;
// The detector's fastest variant on this scene at 1 and 2 threads (docs/architecture.md).
const char* const kVariant = "particle/sorted/full/static";
// nanoflann's default leaf size and the one that ran fastest here on the paper scene.
constexpr std::int64_t kLeafSizes[] = {10, 24};

// The rows that differ between the two canonical contact lists (0 where they are equal).
std::uint64_t rows_differing(const cl::ContactList& a, const cl::ContactList& b) {
  if (a.particle_count() != b.particle_count()) return ~std::uint64_t{0};
  std::uint64_t differing = 0;
  for (std::size_t i = 0; i < a.particle_count(); ++i) {
    const auto ra = a.partners_of(i), rb = b.partners_of(i);
    differing += !std::equal(ra.begin(), ra.end(), rb.begin(), rb.end());
  }
  return differing;
}

void report(benchmark::State& state, double first, double second, std::uint64_t pairs) {
  const double iterations = static_cast<double>(state.iterations());
  state.counters["build_or_T_s"] = first / iterations;
  state.counters["search_or_T_c"] = second / iterations;
  state.counters["contacts"] = static_cast<double>(pairs);
  state.SetLabel(std::to_string(paper_scene().size()) + " particles");
}

void detector_search(benchmark::State& state) {
  const cl::DetectOptions options{cl::parse_variant(kVariant), kDiameter,
                                  static_cast<int>(state.range(0)), nullptr};
  cl::ContactDetector detector;
  detector.run(paper_scene(), options);  // warm-up: buffers and pages
  double setup = 0.0, detect = 0.0;
  std::uint64_t pairs = 0;
  for (auto _ : state) {
    const cl::DetectRun run = detector.run(paper_scene(), options);
    state.SetIterationTime(run.total_s());
    setup += run.setup_s;
    detect += run.detect_s;
    pairs = run.contact_pairs;
  }
  report(state, setup, detect, pairs);
}

void nanoflann_search(benchmark::State& state) {
  const auto threads = static_cast<int>(state.range(0));
  const auto leaf = static_cast<std::size_t>(state.range(1));
  cl::baseline::NanoflannContacts search;
  search.run(paper_scene(), kDiameter, threads, leaf);  // warm-up
  double build = 0.0, queries = 0.0;
  for (auto _ : state) {
    const cl::baseline::NanoflannRun run = search.run(paper_scene(), kDiameter, threads, leaf);
    state.SetIterationTime(run.total_s());
    build += run.build_s;
    queries += run.search_s;
  }
  report(state, build, queries, search.contacts().pair_count());
}

}  // namespace

int run(int argc, char** argv) {
  // The error first: both contact lists, compared row by row.
  const cl::Scene& scene = paper_scene();
  cl::ContactDetector reference;
  reference.run(scene, {cl::parse_variant(kVariant), kDiameter, 1, nullptr});
  cl::baseline::NanoflannContacts search;
  search.run(scene, kDiameter, 1, static_cast<std::size_t>(kLeafSizes[0]));
  const std::uint64_t differing =
      rows_differing(reference.canonical_contacts(), cl::canonicalize(search.contacts(), {}));
  if (differing != 0) {
    std::fprintf(stderr, "neighbour_search_benchmark: %llu rows differ between %s and nanoflann\n",
                 static_cast<unsigned long long>(differing), kVariant);
    return 1;
  }
  benchmark::AddCustomContext("rows_differing_from_nanoflann", "0");
  benchmark::AddCustomContext("git_commit", std::string(cl::build_info().git_commit) +
                                                (cl::build_info().git_dirty ? " (dirty)" : ""));
  benchmark::AddCustomContext("detector_variant", kVariant);
  benchmark::AddCustomContext("simd_target", cl::simd_target());
  benchmark::AddCustomContext("nanoflann_version",
                              std::to_string(NANOFLANN_VERSION >> 8) + "." +
                                  std::to_string((NANOFLANN_VERSION >> 4) & 15) + "." +
                                  std::to_string(NANOFLANN_VERSION & 15));

  const int cores = omp_get_num_procs();
  auto* ours = benchmark::RegisterBenchmark("search/contactlab", detector_search);
  ours->ArgName("threads")->Arg(1)->UseManualTime()->Unit(benchmark::kMillisecond);
  if (cores > 1) ours->Arg(cores);
  auto* theirs = benchmark::RegisterBenchmark("search/nanoflann", nanoflann_search);
  theirs->ArgNames({"threads", "leaf"})->UseManualTime()->Unit(benchmark::kMillisecond);
  for (const std::int64_t leaf : kLeafSizes) {
    theirs->Args({1, leaf});
    if (cores > 1) theirs->Args({cores, leaf});
  }
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "neighbour_search_benchmark: %s\n", e.what());
    return 1;
  }
}
