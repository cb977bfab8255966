// contactlab-cachesim: one contact detection with callgrind's data collection switched on
// around the detection loop only. `contactlab detect --cache-sim` (and sweeps with cache_sim)
// run it under valgrind on a scene they wrote to a temporary file.
//
// Why a second program: it is built from the same kernel sources as contactlab but without
// AVX-512 (valgrind 3.19 cannot execute AVX-512 instructions, so a -march=native binary dies
// with SIGILL under it on AVX-512 CPUs). Its instruction set is CONTACTLAB_CACHESIM_ISA.
#include <fmt/core.h>

#include <CLI/CLI.hpp>

#include "contactlab/kernels/detector.hpp"
#include "contactlab/kernels/error.hpp"
#include "contactlab/kernels/scene_io.hpp"
#include "contactlab/kernels/simd.hpp"

#if CONTACTLAB_HAVE_CALLGRIND_H
#include <valgrind/callgrind.h>
#endif

namespace cl = contactlab;

namespace {

// callgrind's collection state is per thread, so every OpenMP thread toggles its own.
class CallgrindRegion final : public cl::DetectionObserver {
 public:
#if CONTACTLAB_HAVE_CALLGRIND_H
  void thread_begin(int) override { CALLGRIND_TOGGLE_COLLECT; }
  void thread_end(int) override { CALLGRIND_TOGGLE_COLLECT; }
#endif
};

bool running_under_valgrind() {
#if CONTACTLAB_HAVE_CALLGRIND_H
  return RUNNING_ON_VALGRIND != 0;
#else
  return false;
#endif
}

}  // namespace

// Exceptions other than those caught below are bugs: std::terminate, which names them, ends
// the program.
int main(int argc, char** argv) {  // NOLINT(bugprone-exception-escape)
  CLI::App app{
      "contactlab-cachesim: one detection under valgrind's cache simulator (run by "
      "contactlab detect --cache-sim)"};
  std::string scene_file, variant_text;
  double diameter = 0.0;
  int threads = 1;
  bool print_isa = false;
  app.add_option("--scene-file", scene_file, "binary scene (docs/file-formats.md)");
  app.add_option("--diameter", diameter, "particle diameter D");
  app.add_option("--variant", variant_text, "detection variant");
  app.add_option("--threads", threads, "OpenMP threads");
  app.add_flag("--print-isa", print_isa, "print the instruction set this program was built for");
  try {
    app.parse(argc, argv);
    if (print_isa) {
      fmt::print("{}\n", CONTACTLAB_CACHESIM_ISA);
      return 0;
    }
    if (!running_under_valgrind()) {
      throw cl::InputError(
          "contactlab-cachesim runs under valgrind, started by `contactlab detect --cache-sim`");
    }
    if (scene_file.empty() || variant_text.empty() || threads < 1) {
      throw cl::InputError("--scene-file, --variant and --threads >= 1 are needed");
    }
    const cl::Variant variant = cl::parse_variant(variant_text);
    const cl::Scene scene = cl::read_binary_scene(scene_file);
    CallgrindRegion region;
    cl::ContactDetector detector;
    const cl::DetectRun run = detector.run(scene, {variant, diameter, threads, &region});
    // Read by the parent (simulate_caches): the simulated run's own work, which can differ from
    // the native run's (no SIMD here, so no tiles), and the SIMD target it ran.
    fmt::print("contacts {}\ncandidate_tests {}\nsimd_target {}\n", run.contact_pairs,
               run.candidate_tests, cl::simd_target());
    return 0;
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const cl::InputError& e) {
    fmt::print(stderr, "contactlab-cachesim: error: {}\n", e.what());
    return 2;
  }
}
