// `contactlab emulate threads`: detection at thread counts this machine does not have, by
// replaying each variant's trace under its schedule (tuner_model/emulation.hpp), with the
// emulation checked against what this machine can measure. Every value it returns for a thread
// count is labelled: measured (timed here) or emulated.
#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "contactlab/kernels/scene.hpp"
#include "contactlab/kernels/variant.hpp"
#include "contactlab/support/statistics.hpp"
#include "contactlab/tuner/bandwidth_probe.hpp"
#include "contactlab/tuner/tune.hpp"
#include "contactlab/tuner_model/detection_traffic.hpp"

namespace contactlab::tuner {

struct ThreadEmulationOptions {
  std::vector<Variant> variants;
  std::vector<int> threads{1, 2, 4, 8, 16};  // emulated
  std::vector<int> measured_threads{1, 2};   // timed here (1 first: the anchor)
  int rounds = 7;                            // interleaved rounds of timed runs
  // The chunk study: the best chunk of each kind at these thread counts, for the first
  // particle/sorted/full variant's structure (the paper's Table 7 loop).
  std::vector<int> chunk_threads{2, 4, 8, 16};
  std::vector<int> chunk_grid = log2_chunk_grid(65536);
  // With a machine file, every phase (setup, loop, the rows after it) takes at least its bytes
  // (detection_traffic.hpp) over the bandwidth its threads draw: docs/emulation.md, "Bandwidth".
  std::optional<MemorySystem> memory;
};

struct MeasuredThreads {
  int threads = 1;
  Summary setup_s, detect_s, total_s;
};

struct EmulatedThreads {
  int threads = 1;
  double setup_s = 0.0, detect_s = 0.0, speedup = 0.0, imbalance = 0.0;
  double output_s = 0.0;  // of detect_s: the rows copied after the loop
  // A chunked deal's locality factor on the loop (1: a static block, one thread, or guided):
  // thread 0's share of the deal timed alone at one thread over its replay (thread_emulation.cpp).
  double locality = 1.0;
  // Of detect_s: the rest of the assembly after the loop (offsets, reverse entries), fitted as
  // serial + parallel / P from its measured times.
  double assembly_s = 0.0;
  // With a machine file: the bandwidth at this thread count and the bytes of every phase over it.
  double bytes_per_s = 0.0, memory_s = 0.0;
  double total_s() const { return setup_s + detect_s; }
};

struct EmulationCheck {
  int threads = 2;
  double measured_total_s = 0.0, emulated_total_s = 0.0;
  double measured_detect_s = 0.0, emulated_detect_s = 0.0;
};

struct VariantEmulation {
  Variant variant;
  double anchor_scale = 1.0;  // AnchoredLoop::scale of its loop
  std::vector<MeasuredThreads> measured;
  std::vector<EmulatedThreads> emulated;
  std::vector<EmulationCheck> checks;  // at each measured thread count above 1
  DetectionTraffic traffic;            // with a machine file
};

struct EmulatedChunkStudy {
  int threads = 1;
  Variant variant;                               // with the study's kind and a placeholder chunk
  std::vector<std::pair<int, double>> detect_s;  // (chunk, emulated T_c)
  std::vector<std::pair<int, double>> locality;  // (chunk, locality factor in that T_c)
  int best_chunk = 0;
  double best_detect_s = 0.0;
  double block_detect_s = 0.0;  // static block of the same structure
  // dynamic only: the classic formulas' chunks (chunk_formulas.hpp) for this thread count, each
  // emulated as dynamic,k: {name, chunk, T_c}.
  struct Classic {
    std::string name;
    int chunk = 0;
    double detect_s = 0.0;
  };
  std::vector<Classic> classic;
};

struct ThreadEmulation {
  std::vector<VariantEmulation> variants;
  std::vector<EmulatedChunkStudy> chunk_study;
  Calibration calibration;
};

// Throws InputError for no variants, measured threads not starting with 1, a thread count < 1
// or rounds < 1 (before anything is timed or calibrated).
void validate(const ThreadEmulationOptions& options);

// The structures (loops, orders, stencils, precisions) the variants need calibrated: pass to
// machine_calibration (auto_variant.hpp) with the largest measured thread count.
TuneOptions structures_for(const std::vector<Variant>& variants);

// Times every variant at options.measured_threads in `rounds` interleaved rounds (one warm-up
// run each first) and emulates options.threads with the machine costs of `calibration` (fitted
// on the small calibration scenes, never on this one). A chunked deal at P threads (the
// variants' and the chunk study's) is also timed as thread 0's share alone at one thread, in
// the same rounds: its locality factor. Validates the options first.
ThreadEmulation emulate_threads(const Scene& scene, double diameter,
                                const ThreadEmulationOptions& options,
                                const Calibration& calibration);

// A measured median with its 95% interval as the emulation files write it (docs/emulation.md):
// {median, low, high, level, repetitions}.
nlohmann::json interval_json(const Summary& summary);

// The document `emulate threads --json` writes (docs/emulation.md).
nlohmann::json emulation_document(const ThreadEmulation& emulation,
                                  const ThreadEmulationOptions& options, const Context& context,
                                  const SceneRecord& scene);

}  // namespace contactlab::tuner
