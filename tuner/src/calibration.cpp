// Calibration of the schedule model's machine costs: a small fixed set of timed runs of every
// structure on this machine, fitted per structure (cost_calibration.hpp), once per machine and
// build (the tuning cache keeps it).
#include <fmt/core.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <random>
#include <vector>

#include "contactlab/kernels/scene_generate.hpp"
#include "contactlab/support/statistics.hpp"
#include "contactlab/tuner/measured_kernel.hpp"
#include "contactlab/tuner/tune.hpp"
#include "contactlab/tuner_model/cost_calibration.hpp"
#include "methods/methods.hpp"

namespace contactlab::tuner {
namespace {

// Timed runs per calibration point; their median is fitted (a single run on a shared VM can
// take twice as long when a vCPU is stolen).
constexpr int kCalibrationSamples = 5;

WorkView view_of(const LoopWork& work) { return {work.tests, work.homes, work.builds}; }

// The loop's part of T_c in one run: what the loop constants are fitted to (the rows written
// after it are the output term's).
double loop_seconds(DetectionKernel& kernel, const Variant& variant, int threads) {
  const KernelRun r = kernel.run(variant, threads);
  return r.phase_s("detect") - r.phase_s("assembly");
}

// The output's entry-weighted degree (as the model estimates it) and the assembly's seconds
// per copied entry per thread (assembly x threads / copied entries: each thread writes the
// rows of its own finds) of one structure on one scene, the median of kCalibrationSamples
// static runs after a warm-up. Where none is copied (the full stencil at one thread writes its
// rows in place, and the model prices no output for it) the assembly's rest, its row offsets,
// is stored per entry: a floor for predictions at more threads from this point alone.
std::pair<double, double> assembly_per_entry(DetectionKernel& kernel, const Variant& structure,
                                             int threads) {
  Variant v = structure;
  v.schedule = Schedule{};
  kernel.run(v, threads);
  std::vector<double> per_entry;
  std::uint64_t entries = 0;
  const double share = kernel.copied_output_share(v, threads);
  for (int k = 0; k < kCalibrationSamples; ++k) {
    const KernelRun r = kernel.run(v, threads);
    for (const auto& [name, count] : r.counts) {
      if (name == "contact_pairs") entries = 2 * count;
    }
    const double copied = static_cast<double>(entries) * (share > 0.0 ? share : 1.0);
    per_entry.push_back(entries == 0 ? 0.0 : r.phase_s("assembly") * threads / copied);
  }
  return {kernel.estimated_output().degree, median(per_entry)};
}

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
  // The grid alone: 2,000 particles in 200^3 cells, where the cell loop's time is its empty
  // iterations (about 1 ns a key on the EPYC VM, at 100^3 to 200^3 cells alike). In the scenes
  // above they are a fifth of the time or less, and the fit traded them for homes and builds
  // (0.36 ns a key): the cell loop's full stencil came out 13 % faster than measured on the
  // 1,024,000-particle scenes (7.9 M keys), and on the off-centre blob the model chose it over
  // the particle loop, which ran 12 % faster.
  add_scene(SceneKind::kUniform, 2'000, 1.0 / 200.0, sparse_terms);
  // The output term (output_cost.hpp): the assembly per entry at a high entry-weighted degree
  // (the 120,000-particle clustered scene above: the paper's law at the paper's N D^3, up to 350
  // particles per cell) and at a low one: 250,000 uniform particles with about 120 contacts
  // each (D^3 N = 30), 30 M entries, at most 53 particles per cell. Its loop is fitted too:
  // about 800 tests a home, where the tests are nearly all of the time. Without it the per-test
  // constant traded places with the per-home and per-build ones from one calibration to the
  // next (cell/morton/full: 0.04 to 0.37 ns a test), and a dense scene's prediction with it (the
  // off-centre blob's chosen variant ran 2.4x its prediction, 15.6 % slower than the best).
  constexpr std::size_t kHighDegreeScene = 1;
  // The same particles at 1.26 D (D^3 N = 60): the same homes with twice the tests, so that the
  // per-test constant is told from the per-home one by the difference of the two, whatever else
  // the fit does (with one such scene cell/morton/full still came out at 0.006 ns a test and
  // 190 ns a home in one calibration of three).
  add_scene(SceneKind::kUniform, 250'000, std::cbrt(60.0 / 250'000.0), sparse_terms);
  add_scene(SceneKind::kUniform, 250'000, std::cbrt(30.0 / 250'000.0), sparse_terms);
  const std::size_t low_degree_scene = scenes.size() - 1;
  std::deque<DetectionKernel> kernels;  // one per scene, each with its own buffers
  for (const CalibrationScene& c : scenes) kernels.emplace_back(c.scene, c.diameter);
  Calibration calibration;
  calibration.source = "calibrated now";
  calibration.threads = threads;
  std::vector<int> thread_counts{1};
  if (threads > 1) thread_counts.push_back(threads);
  // Every point (structure, schedule, thread count) of a scene is timed once per round, the
  // rounds in a new seeded order each, scene after scene: a noisy spell of the machine then
  // falls on all structures alike. Timed one structure after another, a spell had made one
  // structure's constants 10 - 20 % off against another's, and the model chose between them
  // wrongly (docs/tuning.md).
  const std::vector<Variant> structures = structures_of(options);
  struct Point {
    std::size_t structure, scene;
    int threads;
    Schedule schedule;
    std::vector<double> loop_s;
  };
  std::vector<Point> points;
  std::vector<std::vector<LoopWork>> works(structures.size());  // kept alive: TimedRun views
  for (std::size_t st = 0; st < structures.size(); ++st) {
    for (std::size_t s = 0; s < scenes.size(); ++s) {
      works[st].push_back(kernels[s].iteration_work(structures[st], 1));
      for (const int t : thread_counts) {
        for (const Schedule& schedule : scenes[s].schedules)
          points.push_back({st, s, t, schedule, {}});
      }
    }
  }
  auto variant_of = [&](const Point& p) {
    Variant v = structures[p.structure];
    v.schedule = p.schedule;
    return v;
  };
  std::mt19937_64 random(20261203);
  for (std::size_t s = 0; s < scenes.size(); ++s) {
    std::vector<Point*> order;
    for (Point& p : points) {
      if (p.scene == s) order.push_back(&p);
    }
    for (Point* p : order) kernels[s].run(variant_of(*p), p->threads);  // warm-up
    for (int round = 0; round < kCalibrationSamples; ++round) {
      std::shuffle(order.begin(), order.end(), random);
      for (Point* p : order)
        p->loop_s.push_back(loop_seconds(kernels[s], variant_of(*p), p->threads));
    }
  }
  for (std::size_t st = 0; st < structures.size(); ++st) {
    const Variant& structure = structures[st];
    std::vector<TimedRun> runs;
    for (const Point& p : points) {
      if (p.structure != st) continue;
      runs.push_back({view_of(works[st][p.scene]), p.threads, p.schedule, median(p.loop_s)});
    }
    const CalibrationResult fit = calibrate_costs(runs);
    std::vector<OutputCost> output;
    for (const int t : thread_counts) {
      const auto [low_degree, low_per_entry] =
          assembly_per_entry(kernels[low_degree_scene], structure, t);
      const auto [high_degree, high_per_entry] =
          assembly_per_entry(kernels[kHighDegreeScene], structure, t);
      output.push_back({t, low_degree, low_per_entry, high_degree, high_per_entry});
    }
    calibration.structures[structure_key(structure)] = {
        fit.costs, fit.rms_relative_error, static_cast<int>(runs.size()), std::move(output)};
  }
  calibration.seconds = omp_get_wtime() - start;
  return calibration;
}

}  // namespace contactlab::tuner
