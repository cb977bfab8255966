// Calibration of the schedule model's machine costs: a small fixed set of timed runs of every
// structure on this machine, fitted per structure (cost_calibration.hpp), once per machine and
// build (the tuning cache keeps it).
#include <fmt/core.h>
#include <omp.h>

#include <deque>

#include "contactlab/kernels/scene_generate.hpp"
#include "contactlab/tuner/measured_kernel.hpp"
#include "contactlab/tuner/tune.hpp"
#include "contactlab/tuner_model/cost_calibration.hpp"
#include "contactlab/tuner_model/statistics.hpp"
#include "methods/methods.hpp"

namespace contactlab::tuner {
namespace {

// Timed runs per calibration point; their median is fitted (a single run on a shared VM can
// take twice as long when a vCPU is stolen).
constexpr int kCalibrationSamples = 5;

WorkView view_of(const LoopWork& work) { return {work.tests, work.homes, work.builds}; }

}  // namespace

std::string structure_key(const Variant& variant) {
  // fmt rather than operator+: GCC 12 warns falsely (-Wrestrict) on the concatenation here.
  // The grid index only when named (grid=auto keys, as before it existed, stay valid).
  return fmt::format(
      "{}/{}/{}{}{}", to_string(variant.loop), to_string(variant.order), to_string(variant.stencil),
      variant.precision != Precision::kDouble ? fmt::format("/{}", to_string(variant.precision))
                                              : std::string(),
      variant.grid != GridIndex::kAuto ? fmt::format("/grid={}", to_string(variant.grid))
                                       : std::string());
}

Calibration calibrate_machine(const TuneOptions& options, int threads) {
  const double start = omp_get_wtime();
  // Two sizes of one dense clustered scene, timed under schedules that exercise every cost
  // term, separate time per pair test from the fixed costs. A sparse uniform scene (about 0.1
  // particles per cell, few tests per particle) identifies the costs of homes and of
  // neighbour-range builds in a grid larger than the caches, which dominate sparse scenes and
  // which dense scenes alone leave free; block, block-cyclic and dynamic suffice there. Each
  // is small enough to calibrate in seconds.
  const std::vector<Schedule> every_term{{ScheduleKind::kStatic, 0},  {ScheduleKind::kStatic, 1},
                                         {ScheduleKind::kStatic, 64}, {ScheduleKind::kStatic, 4096},
                                         {ScheduleKind::kDynamic, 1}, {ScheduleKind::kDynamic, 64},
                                         {ScheduleKind::kGuided, 64}};
  const std::vector<Schedule> sparse_terms{
      {ScheduleKind::kStatic, 0}, {ScheduleKind::kStatic, 64}, {ScheduleKind::kDynamic, 64}};
  struct CalibrationScene {
    Scene scene;
    double diameter;
    const std::vector<Schedule>& schedules;
  };
  std::vector<CalibrationScene> scenes;
  auto add_scene = [&](SceneKind kind, std::uint64_t n, double diameter,
                       const std::vector<Schedule>& schedules) {
    SceneSpec spec;
    spec.kind = kind;
    spec.n = n;
    spec.diameter = diameter;
    scenes.push_back({generate_scene(spec), diameter, schedules});
  };
  add_scene(SceneKind::kClustered, 40'000, 1.0 / 100.0, every_term);
  add_scene(SceneKind::kClustered, 120'000, 1.0 / 100.0, every_term);
  add_scene(SceneKind::kUniform, 300'000, 1.0 / 150.0, sparse_terms);
  std::deque<DetectionKernel> kernels;  // one per scene, each with its own buffers
  for (const CalibrationScene& c : scenes) kernels.emplace_back(c.scene, c.diameter);
  Calibration calibration;
  calibration.source = "calibrated now";
  calibration.threads = threads;
  std::vector<int> thread_counts{1};
  if (threads > 1) thread_counts.push_back(threads);
  for (const Variant& structure : structures_of(options)) {
    std::vector<LoopWork> works;  // kept alive: TimedRun holds views
    for (DetectionKernel& kernel : kernels) works.push_back(kernel.iteration_work(structure, 1));
    std::vector<TimedRun> runs;
    for (std::size_t s = 0; s < scenes.size(); ++s) {
      for (const int t : thread_counts) {
        for (const Schedule& schedule : scenes[s].schedules) {
          Variant v = structure;
          v.schedule = schedule;
          kernels[s].run(v, t);  // warm-up
          runs.push_back({view_of(works[s]), t, schedule,
                          median(kernels[s].samples(v, t, kCalibrationSamples))});
        }
      }
    }
    const CalibrationResult fit = calibrate_costs(runs);
    calibration.structures[structure_key(structure)] = {fit.costs, fit.rms_relative_error,
                                                        static_cast<int>(runs.size())};
  }
  calibration.seconds = omp_get_wtime() - start;
  return calibration;
}

}  // namespace contactlab::tuner
