// The tuner: picks the variant and the chunk size for a scene, a diameter and a thread count,
// three ways side by side (docs/tuning.md):
//  - model: zero timed runs on the scene; the exact per-iteration work (cell occupancy) and
//    a per-machine calibrated cost model predict the best schedule and chunk;
//  - search: screens the loop/order/stencil variants at the model's schedule, then a
//    noise-aware search over the chunk size seeded by the model;
//  - exhaustive: every chunk of the grid (ground truth for the regret of the other two).
// They are plug-ins (tuning_method.hpp) over "a kernel" (measured_kernel.hpp).
#pragma once

#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "contactlab/kernels/scene.hpp"
#include "contactlab/kernels/variant.hpp"
#include "contactlab/tuner/progress.hpp"
#include "contactlab/tuner/result_schema.hpp"
#include "contactlab/tuner/tune_report.hpp"
#include "contactlab/tuner_model/output_cost.hpp"
#include "contactlab/tuner_model/schedule_model.hpp"

namespace contactlab::tuner {

struct TuneOptions {
  int threads = 0;  // 0 = resolve_threads(0), OpenMP's default
  std::vector<int> chunk_grid = log2_chunk_grid(65536);
  std::vector<LoopKind> loops{LoopKind::kParticle, LoopKind::kCell};
  // Unsorted is left out by default: reordering is faster on every scene measured (paper
  // Tables 2-5, ours in results/). So is Morton: its best structure ran 1.1 - 2.4x as long as
  // the sorted order's best on the paper, uniform, core and off-centre blob scenes at 1 and 2
  // threads (docs/tuning.md), and the model priced it too low on the blob. Pass either
  // explicitly to screen it too.
  std::vector<Order> orders{Order::kSorted};
  std::vector<Stencil> stencils{Stencil::kFull, Stencil::kHalf};
  // Single precision is screened on request (`tune --float`); its variants decide the pairs
  // within float rounding of touching in double, so they find the exact contacts too.
  std::vector<Precision> precisions{Precision::kDouble};
  // The cell index: auto (the scene's rule, use_hashed_index) unless asked to screen dense and
  // hashed, which runs each structure twice (dense only where the grid fits a dense table).
  std::vector<GridIndex> grids{GridIndex::kAuto};
  // Wrong contact pairs a variant may have against the double-precision result and still be
  // chosen (the search checks every screened variant); 0 = exact only.
  std::uint64_t tolerance = 0;
  bool predict_only = false;   // the model alone: no timed run on the scene
  bool exhaustive = false;     // also sweep the whole chunk grid (ground truth, costly)
  int search_samples = 3;      // timed runs per chunk evaluated by the search
  int exhaustive_rounds = 10;  // rounds over the whole chunk grid, one timed run per chunk each
  // Rounds of the final verification: every distinct choice timed once per round, in a new
  // random order each round; regrets compare within rounds (statistics.hpp, RoundSlowdowns).
  int verify_rounds = 30;
  // Extra thread counts for which the model predicts the best chunk (labelled predicted).
  std::vector<int> predict_threads{4, 8, 16};
};

// Machine costs of the schedule model for each loop/order/stencil/precision ("structure":
// a variant without its schedule), fitted once per machine and build, and cached.
struct StructureCosts {
  MachineCosts costs;
  double rms_relative_error = 0.0;
  int runs = 0;
  // The output's cost past the caches (output_cost.hpp), at 1 and the calibrated threads.
  std::vector<OutputCost> output;
};

struct Calibration {
  std::map<std::string, StructureCosts> structures;  // key: structure_key(variant)
  std::string source;    // "calibrated now", "cache", "defaults (not calibrated)"
  double seconds = 0.0;  // spent calibrating
  int threads = 0;       // the largest thread count used
};

// "loop/order/stencil[/float]": a variant without its schedule.
std::string structure_key(const Variant& variant);

// Times a small fixed set of runs of every structure of `options` on this machine (a clustered
// scene of N = 120,000 at D = 1/100, two dense uniform ones of N = 80,000, a sparse uniform one
// and a nearly empty grid; static, static,k, dynamic,k, guided,k at 1 and `threads` threads;
// every point of a scene once per round, in a new seeded order each round, three rounds and up to
// five for points whose samples spread) and fits each structure's loop costs to the loop's time;
// its output costs (output_cost.hpp) from the assembly's time per entry in the block runs of the
// clustered scene and of the sparser dense uniform one, whose rows exceed the caches
// (docs/tuning.md). `progress`, when given, hears the share done and the seconds left after
// every timed run.
Calibration calibrate_machine(const TuneOptions& options, int threads,
                              const ProgressMeter& progress = {});

struct TuneReport {
  TuneDocument document;  // the tune.json document (docs/tuning.md)
  Variant chosen;         // what `--variant auto` uses: the search's choice (the model's with
                          // predict_only)
};

class MeasuredKernel;

// Tunes any kernel with the registered methods (tuning_method.hpp); `scene` and `diameter`
// describe what the kernel runs on, for the report. Throws InputError for bad options.
TuneReport tune_kernel(MeasuredKernel& kernel, const SceneRecord& scene,
                       std::optional<double> diameter, const TuneOptions& options,
                       const Calibration& calibration, const std::string& command_line);

// Contact detection of `scene`. Throws InputError for bad options. `scene_record` describes the
// scene for the report.
TuneReport tune(const Scene& scene, const SceneRecord& scene_record, double diameter,
                const TuneOptions& options, const Calibration& calibration,
                const std::string& command_line);

// The tuning cache: a JSON file (default $CONTACTLAB_CACHE_DIR, else $XDG_CACHE_HOME/contactlab,
// else ~/.cache/contactlab, file tuning.json) holding calibrations per machine and build, and
// choices per (machine, build, scene checksum, N, D, threads).
class TuningCache {
 public:
  explicit TuningCache(std::string path = default_path());
  static std::string default_path();
  const std::string& path() const { return path_; }

  std::optional<Calibration> calibration() const;
  void store_calibration(const Calibration& calibration);
  // `setting` (empty for one process) tells runs of the same scene apart that divide it
  // otherwise, e.g. "mpi decomposed, 4 ranks, halo 0.01": their choices are separate entries.
  std::optional<Variant> choice(const SceneRecord& scene, double diameter, int threads,
                                const std::string& setting = {}) const;
  void store_choice(const SceneRecord& scene, double diameter, int threads, const Variant& variant,
                    double seconds, const std::string& setting = {});

  // A calibration as the cache stores it (JSON text) and back, strictly: for processes that
  // share one calibration without each reading the file (MPI ranks).
  static std::string calibration_text(const Calibration& calibration);
  static Calibration calibration_from_text(const std::string& text);

 private:
  nlohmann::json load() const;
  void save(const nlohmann::json& document) const;
  std::string path_;
};

}  // namespace contactlab::tuner
