// Calibration of the schedule model's machine costs: a small fixed set of timed runs of every
// structure on this machine, fitted per structure (cost_calibration.hpp), once per machine and
// build (the tuning cache keeps it). What it times and why that is enough: docs/tuning.md,
// "Calibration".
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

// Timed runs per calibration point: kMinSamples, more (up to kMaxSamples) while no other sample
// lies within kAgreement of their median. The median is fitted: a single run on a shared VM can
// take twice as long when a vCPU is stolen, and the median of three that two samples agree on
// ignores such a run; where they all disagree, more samples decide. A quiet machine stops
// nearly every point at three, a busy one pays more where it needs them.
constexpr std::size_t kMinSamples = 3;
constexpr std::size_t kMaxSamples = 5;
constexpr double kAgreement = 0.05;

WorkView view_of(const LoopWork& work) { return {work.tests, work.homes, work.builds}; }

bool settled(const std::vector<double>& samples) {
  if (samples.size() < kMinSamples) return false;
  if (samples.size() >= kMaxSamples) return true;
  // The median and the samples within kAgreement of it (the median's own sample among them
  // where the count is odd): two such settle the point.
  const double m = median(samples);
  std::size_t agreeing = 0;
  for (const double x : samples) agreeing += std::abs(x - m) <= kAgreement * m;
  return agreeing >= 2;
}

struct CalibrationScene {
  SceneSpec spec;
  const std::vector<Schedule>& schedules;
  // Also timed under the balanced schedule at more than one thread, for its weighing alone.
  bool weighed = false;
};

// One point: a structure on a scene under a schedule at a thread count, its samples of the
// loop's time (T_c less the assembly after it: what the loop constants are fitted to) and, for
// the output term, of the assembly.
struct Point {
  std::size_t structure = 0, scene = 0;
  int threads = 1;
  Schedule schedule;
  std::vector<double> loop_s, assembly_s;
  std::vector<double> weigh_s;  // the balanced schedule's weighing (0 for other schedules)
  std::uint64_t entries = 0;    // the output's, two per contact pair
  double last_run_s = -1.0;     // the last run's wall time (the time-left estimate), -1 before one
};

// A balanced run is there for its weighing alone: its samples are the weighing's.
bool is_weighing(const Point& p) { return p.schedule.kind == ScheduleKind::kBalanced; }
const std::vector<double>& samples_of(const Point& p) {
  return is_weighing(p) ? p.weigh_s : p.loop_s;
}

// The estimate of the time left: every run still planned priced at its point's last run, else at
// its structure's warm-up on the scene, else at `prior_s` (the work priced by the default machine
// costs) times what the runs so far took against their priors.
class TimeLeft {
 public:
  void ran(double prior_s, double seconds) {
    prior_done_s_ += prior_s;
    done_s_ += seconds;
  }
  double scaled(double prior_s) const {
    return prior_done_s_ > 0.0 ? prior_s * done_s_ / prior_done_s_ : prior_s;
  }

 private:
  double prior_done_s_ = 0.0, done_s_ = 0.0;
};

// What a run of `work` at `threads` should take with MachineCosts' defaults, with the setup (one
// registration and reordering per run) and the rows' writing at about 30 ns a particle: only the
// proportions between points matter (TimeLeft scales them).
double prior_seconds(const LoopWork& work, std::size_t particles, int threads) {
  const MachineCosts c;
  double tests = 0.0, homes = 0.0, builds = 0.0;
  for (const auto t : work.tests) tests += t;
  for (const auto h : work.homes) homes += h;
  for (const auto b : work.builds) builds += b;
  if (work.homes.empty()) homes = static_cast<double>(work.tests.size());
  if (work.builds.empty()) builds = static_cast<double>(work.tests.size());
  const double loop = tests * c.seconds_per_test +
                      static_cast<double>(work.tests.size()) * c.seconds_per_iteration +
                      homes * c.seconds_per_home + builds * c.seconds_per_build;
  return loop / threads + 3e-8 * static_cast<double>(particles);
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

Calibration calibrate_machine(const TuneOptions& options, int threads,
                              const ProgressMeter& progress) {
  const double start = omp_get_wtime();
  // A dense clustered scene timed under schedules that exercise every cost term; a larger one
  // (block only) for the output's cost at a high degree; two dense uniform scenes (the same homes
  // with twice the tests) that tell the per-test constant from the fixed ones; a sparse uniform
  // scene and a nearly empty grid for the costs of homes, of neighbour-range builds and of empty
  // cells. docs/tuning.md ("Calibration") says why each is there and what was left out.
  const std::vector<Schedule> every_term{{ScheduleKind::kStatic, 0},  {ScheduleKind::kStatic, 1},
                                         {ScheduleKind::kStatic, 64}, {ScheduleKind::kStatic, 4096},
                                         {ScheduleKind::kDynamic, 1}, {ScheduleKind::kDynamic, 64},
                                         {ScheduleKind::kGuided, 64}};
  const std::vector<Schedule> sparse_terms{
      {ScheduleKind::kStatic, 0}, {ScheduleKind::kStatic, 64}, {ScheduleKind::kDynamic, 64}};
  const std::vector<Schedule> dense_terms{{ScheduleKind::kStatic, 0}, {ScheduleKind::kDynamic, 64}};
  const std::vector<Schedule> block{{ScheduleKind::kStatic, 0}};
  auto spec_of = [](SceneKind kind, std::uint64_t n, double diameter) {
    SceneSpec spec;
    spec.kind = kind;
    spec.n = n;
    spec.diameter = diameter;
    return spec;
  };
  const std::vector<CalibrationScene> scenes{
      // Dense cells beside sparse ones, every schedule: chunks, grabs, breaks and cold tests.
      {spec_of(SceneKind::kClustered, 40'000, 1.0 / 100.0), every_term, true},
      // The same law at three times N (the paper's N D^3, up to 350 particles a cell): the
      // output term's high-degree point (output_cost.hpp: entry-weighted degree about 240),
      // and a second size of the first scene for the loop.
      {spec_of(SceneKind::kClustered, 120'000, 1.0 / 100.0), block},
      // Sparse (0.09 particles a cell) in a cell index larger than the caches (13 MB): homes
      // and range builds, which dominate sparse scenes.
      {spec_of(SceneKind::kUniform, 300'000, 1.0 / 150.0), sparse_terms, true},
      // The grid alone: 2,000 particles in 200^3 cells, where the cell loop's time is its empty
      // iterations (about 1 ns a key on the EPYC VM), which the other scenes leave the fit to
      // trade for homes and builds.
      {spec_of(SceneKind::kUniform, 2'000, 1.0 / 200.0), sparse_terms, true},
      // 80,000 uniform particles at D^3 N = 60 and at 30 (about 250 and 125 contacts each, 1,600
      // and 800 tests a home): the same homes with twice the tests. The second is the output
      // term's low-degree point (degree about 120, 10 M entries, 40 MB of rows: past the caches).
      {spec_of(SceneKind::kUniform, 80'000, std::cbrt(60.0 / 80'000.0)), dense_terms},
      {spec_of(SceneKind::kUniform, 80'000, std::cbrt(30.0 / 80'000.0)), dense_terms},
  };
  constexpr std::size_t kHighDegreeScene = 1;
  constexpr std::size_t kLowDegreeScene = 5;
  const std::vector<Variant> structures = structures_of(options);
  std::vector<int> thread_counts{1};
  if (threads > 1) thread_counts.push_back(threads);

  // Every scene and every structure's work (no timing), before the first timed run: the time
  // left is then known from the first runs on.
  std::deque<Scene> scene_data;
  std::deque<DetectionKernel> kernels;  // one per scene, each with its own buffers
  std::vector<std::vector<LoopWork>> works(scenes.size());  // kept alive: TimedRun views
  std::vector<double> degrees(scenes.size(), 0.0);
  for (std::size_t s = 0; s < scenes.size(); ++s) {
    scene_data.push_back(generate_scene(scenes[s].spec));
    kernels.emplace_back(scene_data.back(), scenes[s].spec.diameter);
    for (const Variant& structure : structures)
      works[s].push_back(kernels[s].iteration_work(structure, 1));
    if (s == kHighDegreeScene || s == kLowDegreeScene)
      degrees[s] = kernels[s].estimated_output().degree;
  }

  // Every point (structure, schedule, thread count) of a scene is timed once per round, the
  // rounds in a new seeded order each, scene after scene: a noisy spell of the machine then
  // falls on all structures alike. Timed one structure after another, a spell had made one
  // structure's constants 10 - 20 % off against another's, and the model chose between them
  // wrongly (docs/tuning.md).
  std::vector<Point> points;
  for (std::size_t s = 0; s < scenes.size(); ++s) {
    for (std::size_t st = 0; st < structures.size(); ++st) {
      for (const int t : thread_counts) {
        std::vector<Schedule> schedules = scenes[s].schedules;
        if (scenes[s].weighed && t > 1) schedules.push_back({ScheduleKind::kBalanced, 0});
        for (const Schedule& schedule : schedules) {
          Point p;
          p.structure = st;
          p.scene = s;
          p.threads = t;
          p.schedule = schedule;
          points.push_back(std::move(p));
        }
      }
    }
  }
  auto variant_of = [&](std::size_t structure, const Schedule& schedule) {
    Variant v = structures[structure];
    v.schedule = schedule;
    return v;
  };
  auto warm_index = [&](std::size_t structure, int t) {
    return structure * thread_counts.size() + (t == 1 ? 0 : 1);
  };
  // Per scene, per structure and thread count: the run's prior and the warm-up's wall time (-1
  // before it ran).
  std::vector<std::vector<double>> prior_s(scenes.size()), warm_s(scenes.size());
  for (std::size_t s = 0; s < scenes.size(); ++s) {
    for (std::size_t st = 0; st < structures.size(); ++st) {
      for (const int t : thread_counts) {
        prior_s[s].push_back(prior_seconds(works[s][st], scene_data[s].size(), t));
        warm_s[s].push_back(-1.0);
      }
    }
  }
  auto prior_of = [&](std::size_t scene, std::size_t structure, int t) {
    return prior_s[scene][warm_index(structure, t)];
  };
  TimeLeft time_left;
  auto report = [&] {
    if (!progress) return;
    double left = 0.0;
    for (std::size_t s = 0; s < scenes.size(); ++s) {
      for (std::size_t st = 0; st < structures.size(); ++st) {
        for (const int t : thread_counts) {
          if (warm_s[s][warm_index(st, t)] < 0.0) left += time_left.scaled(prior_of(s, st, t));
        }
      }
    }
    for (const Point& p : points) {
      const std::size_t planned =
          std::max(kMinSamples, p.loop_s.size() + (settled(samples_of(p)) ? 0 : 1));
      const double warm = warm_s[p.scene][warm_index(p.structure, p.threads)];
      const double each = p.last_run_s >= 0.0 ? p.last_run_s
                          : warm >= 0.0
                              ? warm
                              : time_left.scaled(prior_of(p.scene, p.structure, p.threads));
      left += each * static_cast<double>(planned - p.loop_s.size());
    }
    const double elapsed = omp_get_wtime() - start;
    progress(std::min(0.99, elapsed / (elapsed + left)), left);
  };
  auto timed_run = [&](DetectionKernel& kernel, const Variant& variant, int t, double prior,
                       double& wall_s) {
    const double before = omp_get_wtime();
    KernelRun run = kernel.run(variant, t);
    wall_s = omp_get_wtime() - before;
    time_left.ran(prior, wall_s);
    return run;
  };

  std::mt19937_64 random(20261203);
  for (std::size_t s = 0; s < scenes.size(); ++s) {
    // One warm-up per structure and thread count (its buffers faulted in, its data in the
    // caches), not per point: the median of a point's samples absorbs a first run that is slow.
    for (std::size_t st = 0; st < structures.size(); ++st) {
      for (const int t : thread_counts) {
        timed_run(kernels[s], variant_of(st, Schedule{}), t, prior_of(s, st, t),
                  warm_s[s][warm_index(st, t)]);
        report();
      }
    }
    std::vector<Point*> order;
    for (Point& p : points) {
      if (p.scene == s) order.push_back(&p);
    }
    for (std::size_t round = 0; round < kMaxSamples; ++round) {
      std::vector<Point*> due;
      for (Point* p : order) {
        if (!settled(samples_of(*p))) due.push_back(p);
      }
      if (due.empty()) break;
      std::shuffle(due.begin(), due.end(), random);
      for (Point* p : due) {
        const KernelRun r = timed_run(kernels[s], variant_of(p->structure, p->schedule), p->threads,
                                      prior_of(s, p->structure, p->threads), p->last_run_s);
        p->loop_s.push_back(r.phase_s("detect") - r.phase_s("assembly"));
        p->assembly_s.push_back(r.phase_s("assembly"));
        p->weigh_s.push_back(r.phase_s("weigh"));
        for (const auto& [name, count] : r.counts) {
          if (name == "contact_pairs") p->entries = 2 * count;
        }
        report();
      }
    }
  }

  Calibration calibration;
  calibration.source = "calibrated now";
  calibration.threads = threads;
  for (std::size_t st = 0; st < structures.size(); ++st) {
    const Variant& structure = structures[st];
    std::vector<TimedRun> runs;
    std::vector<WeighRun> weighings;
    for (const Point& p : points) {
      if (p.structure != st) continue;
      if (is_weighing(p)) {
        if (median(p.weigh_s) > 0.0)
          weighings.push_back({view_of(works[p.scene][st]), p.threads, median(p.weigh_s)});
        continue;
      }
      runs.push_back({view_of(works[p.scene][st]), p.threads, p.schedule, median(p.loop_s)});
    }
    CalibrationResult fit = calibrate_costs(runs);
    // The balanced schedule's weighing, from its own runs (its loop is not fitted: the loop
    // constants price the blocks it makes). The loop's per-iteration constant holds a home's
    // whole visit, 2.3x what a home's weighing took on the paper scene at two threads, so
    // priced at it the model had made the balanced blocks look slower than they are. At one
    // thread nothing weighs, and the loop's constants stand in (-1).
    if (!weighings.empty()) {
      const WeighingFit weighing = calibrate_weighing(weighings);
      fit.costs.seconds_per_weighed_iteration = weighing.seconds_per_iteration;
      fit.costs.seconds_per_weighed_build = weighing.seconds_per_build;
    }
    // The output term from the block runs of the low- and high-degree scenes above: the
    // assembly's seconds per copied entry per thread (assembly x threads / copied entries: each
    // thread writes the rows of its own finds). Where none is copied (the full stencil at one
    // thread writes its rows in place, and the model prices no output for it) the assembly's
    // rest, its row offsets, is stored per entry: a floor for predictions at more threads from
    // this point alone.
    auto per_entry = [&](std::size_t scene, int t) {
      for (const Point& p : points) {
        if (p.structure != st || p.scene != scene || p.threads != t || p.schedule != Schedule{}) {
          continue;
        }
        const double share = contactlab::copied_output_share(variant_of(st, Schedule{}), t);
        const double copied = static_cast<double>(p.entries) * (share > 0.0 ? share : 1.0);
        std::vector<double> seconds;
        for (const double a : p.assembly_s)
          seconds.push_back(p.entries == 0 ? 0.0 : a * t / copied);
        return median(seconds);
      }
      return 0.0;
    };
    // The half stencil's exchange: the low-degree scene's dynamic,64 assembly against its
    // block's at the same thread count (the dynamic deal passes (t - 1) / t of the reverse
    // entries on; the block's rows are its homes).
    auto assembly_at = [&](int t, const Schedule& schedule) {
      for (const Point& p : points) {
        if (p.structure == st && p.scene == kLowDegreeScene && p.threads == t &&
            p.schedule == schedule)
          return median(p.assembly_s);
      }
      return 0.0;
    };
    std::vector<OutputCost> output;
    output.reserve(thread_counts.size());
    for (const int t : thread_counts) {
      const Schedule passing{ScheduleKind::kDynamic, 64};
      const double exchange =
          passes_reverse_entries_on(variant_of(st, passing), t)
              ? fit_exchange(assembly_at(t, passing), assembly_at(t, Schedule{}), t)
              : 0.0;
      output.push_back({t, degrees[kLowDegreeScene], per_entry(kLowDegreeScene, t),
                        degrees[kHighDegreeScene], per_entry(kHighDegreeScene, t), exchange});
    }
    calibration.structures[structure_key(structure)] = {
        fit.costs, fit.rms_relative_error, static_cast<int>(runs.size()), std::move(output)};
  }
  calibration.seconds = omp_get_wtime() - start;
  return calibration;
}

}  // namespace contactlab::tuner
