#include "contactlab/tuner/sweep.hpp"

#include <fmt/core.h>
#include <omp.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <optional>
#include <set>
#include <string>

#include "contactlab/kernels/atomic_file.hpp"
#include "contactlab/kernels/detector.hpp"
#include "contactlab/kernels/error.hpp"
#include "contactlab/kernels/scene_io.hpp"
#include "contactlab/tuner/cache_sim.hpp"
#include "contactlab/tuner/context.hpp"
#include "contactlab/tuner/measure.hpp"
#include "contactlab/tuner/papi_counters.hpp"

namespace contactlab::tuner {
namespace {

// The exact reference every point is checked against: double precision, half stencil (the
// tests prove every double variant equal to the brute force).
const Variant kReferenceVariant = parse_variant("particle/sorted/half/static");

// What a result file's context says of where and by what its points were measured: the
// machine (the CPU as hwloc or /proc/cpuinfo names it, its cores and caches) and the build.
std::string machine_of(const Context& context) {
  const MachineInfo& m = context.machine;
  std::string model = m.cpu_model;
  model.erase(model.find_last_not_of(' ') + 1);
  std::string text = fmt::format("'{}' ({} cores, {} logical CPUs", model, m.cores, m.pus);
  for (const CacheInfo& cache : m.caches) {
    text += fmt::format(", L{} {} {} KiB", cache.level, cache.type, cache.size_bytes / 1024);
  }
  return text + ")";
}
std::string build_of(const Context& context) {
  const BuildRecord& b = context.build;
  return fmt::format("commit {}{} ({}, {}, flags '{}')", b.git_commit.substr(0, 10),
                     b.git_dirty ? " with local changes" : "", b.compiler, b.build_type, b.flags);
}

// A resumed sweep adds its visits to the file's points under the file's one context, which
// names one machine and one build for all of them: so only on that machine and with that build
// (elsewhere, the points measured before would be labelled as this run's).
void check_resumable(const std::string& path, const Context& file, const Context& now) {
  const std::string file_machine = machine_of(file), machine = machine_of(now);
  const std::string file_build = build_of(file), build = build_of(now);
  std::string mismatch;
  if (file_machine != machine) {
    mismatch = fmt::format("measured on {}, this machine is {}", file_machine, machine);
  } else if (file_build != build) {
    mismatch = fmt::format("measured by the build of {}, this program is {}", file_build, build);
  }
  if (!mismatch.empty()) {
    throw InputError(fmt::format(
        "{}: {}: --resume continues a sweep on the same machine and build only (write to another "
        "--out)",
        path, mismatch));
  }
}

std::string format_duration(double seconds) {
  const long s = std::lround(seconds);
  return s >= 3600 ? fmt::format("{}h{:02}m", s / 3600, s / 60 % 60)
                   : fmt::format("{}m{:02}s", s / 60, s % 60);
}

}  // namespace

std::string point_key(const std::string& scene_checksum, const std::string& variant, int threads) {
  return scene_checksum + "|" + variant + "|" + std::to_string(threads);
}

std::pair<Scene, SceneRecord> load_experiment_scene(const ExperimentScene& scene) {
  if (!scene.file.empty()) {
    Scene loaded = read_scene(scene.file, Box{});
    SceneRecord record = describe_file_scene(scene.file, loaded, scene.diameter);
    return {std::move(loaded), std::move(record)};
  }
  Scene generated = generate_scene(scene.spec);
  SceneRecord record = describe_generated_scene(scene.spec, generated);
  return {std::move(generated), std::move(record)};
}

std::pair<std::uint64_t, std::uint64_t> contact_differences(const ContactList& reference,
                                                            const ContactList& candidate) {
  std::uint64_t missing = 0, extra = 0;
  for (std::size_t i = 0; i < reference.particle_count(); ++i) {
    const auto a = reference.partners_of(i);
    const auto b = candidate.partners_of(i);
    std::size_t p = 0, q = 0;
    // Rows are sorted; count each pair once, from its lower id.
    while (p < a.size() || q < b.size()) {
      if (q == b.size() || (p < a.size() && a[p] < b[q])) {
        missing += a[p++] > i;
      } else if (p == a.size() || b[q] < a[p]) {
        extra += b[q++] > i;
      } else {
        ++p;
        ++q;
      }
    }
  }
  return {missing, extra};
}

SweepSummary run_sweep(const Experiment& experiment, const SweepOptions& options) {
  namespace fs = std::filesystem;
  prepare_output_file(options.out);
  ResultFile result;
  std::optional<Context> resumed;  // the context of the file resumed
  if (fs::exists(options.out)) {
    if (!options.resume) {
      throw InputError(options.out +
                       ": exists; pass --resume to continue that sweep, or choose another file");
    }
    result = read_result_file(options.out);
    resumed = result.context;
    // Failed points are tried again, in every round.
    std::erase_if(result.runs, [](const RunRecord& r) { return r.status == RunStatus::kFailed; });
  }
  const int max_threads = *std::max_element(experiment.threads.begin(), experiment.threads.end());
  result.context = collect_context(options.command_line, max_threads);
  for (const std::string& warning : result.context.warnings)
    fmt::print(stderr, "warning: {}\n", warning);

  SweepSummary summary;
  summary.points = experiment_points(experiment).size();

  // Scenes and their reference contacts, made once each.
  std::vector<std::pair<Scene, SceneRecord>> scenes;
  for (const ExperimentScene& s : experiment.scenes) scenes.push_back(load_experiment_scene(s));
  std::map<std::size_t, ContactList> references;
  ContactDetector detector;
  std::optional<PapiCounters> papi;
  if (experiment.papi) papi.emplace(std::vector<std::string>{});
  std::optional<CacheGeometry> geometry;
  if (!experiment.cache_sim.empty()) geometry = parse_cache_geometry(experiment.cache_sim);

  // Each point's record in result.runs, by key.
  auto key_of = [&](const ExperimentPoint& point) {
    return point_key(scenes[point.scene].second.checksum, to_string(point.variant), point.threads);
  };
  std::map<std::string, std::size_t> record_of;
  for (std::size_t r = 0; r < result.runs.size(); ++r) {
    const RunParameters& p = result.runs[r].parameters;
    record_of[point_key(p.scene.checksum, p.variant, p.threads)] = r;
  }
  // Whether the file already holds the point's visit in `round` (a file without rounds holds
  // round 0 only).
  auto has_round = [&](const ExperimentPoint& point, int round) {
    const auto at = record_of.find(key_of(point));
    if (at == record_of.end()) return false;
    const auto& rounds = result.runs[at->second].samples.round;
    return rounds ? std::find(rounds->begin(), rounds->end(), round) != rounds->end() : round == 0;
  };
  // The visits left, round by round, each round in its own order.
  std::vector<std::pair<int, ExperimentPoint>> todo;
  std::set<std::string> measured;  // points visited in this sweep
  for (const ExperimentPoint& point : experiment_points(experiment)) {
    bool complete = true;
    for (int round = 0; round < experiment.rounds; ++round) complete &= has_round(point, round);
    summary.skipped += complete;
  }
  for (int round = 0; round < experiment.rounds; ++round) {
    for (const ExperimentPoint& point : experiment_points(experiment, round)) {
      if (!has_round(point, round)) todo.emplace_back(round, point);
    }
  }
  if (resumed && !todo.empty()) check_resumable(options.out, *resumed, result.context);
  const bool bar = options.progress && ::isatty(STDERR_FILENO);
  const double start = omp_get_wtime();
  for (std::size_t index = 0; index < todo.size(); ++index) {
    const auto& [round, point] = todo[index];
    const std::string key = key_of(point);
    const auto existing = record_of.find(key);
    // A point that failed in an earlier round of this sweep is not measured again.
    if (existing != record_of.end() && result.runs[existing->second].status == RunStatus::kFailed)
      continue;
    const auto& [scene, scene_record] = scenes[point.scene];
    const double diameter = experiment.scenes[point.scene].diameter;
    if (bar) {
      const double elapsed = omp_get_wtime() - start;
      const double eta = index ? elapsed / double(index) * double(todo.size() - index) : 0.0;
      fmt::print(stderr, "\r\033[K[{}/{}] {:3.0f}%  elapsed {}  ETA {}  {} threads {}{}", index + 1,
                 todo.size(), 100.0 * double(index) / double(todo.size()), format_duration(elapsed),
                 index ? format_duration(eta) : "?", to_string(point.variant), point.threads,
                 experiment.rounds > 1 ? fmt::format("  round {}", round + 1) : "");
    }
    DetectOptions detect{point.variant, diameter, point.threads, nullptr};
    RunParameters parameters{to_string(point.variant), point.threads, scene_record,
                             experiment.repetitions};
    // Counters and simulated caches are not timings: counted at the point's first visit only.
    const bool first_visit = existing == record_of.end();
    RunRecord run;
    try {
      MeasureOptions measure;
      measure.repetition = experiment.repetitions;
      measure.papi = papi && first_visit ? &*papi : nullptr;
      if (experiment.check_contacts && !references.count(point.scene)) {
        detector.run(scene, DetectOptions{kReferenceVariant, diameter, point.threads, nullptr});
        references[point.scene] = detector.canonical_contacts();
      }
      run = measure_detection(detector, scene, scene_record, detect, measure);
      if (geometry && first_visit) {
        run.counters.push_back(
            simulate_detection_caches(scene, diameter, point.variant, point.threads, *geometry));
      }
      if (experiment.check_contacts && run.status != RunStatus::kFailed) {
        const auto [missing, extra] =
            contact_differences(references[point.scene], detector.canonical_contacts());
        run.contact_check = ContactCheck{to_string(kReferenceVariant), missing, extra};
        if ((missing || extra) && point.variant.precision == Precision::kDouble) {
          run.status = RunStatus::kInvalid;
          run.message = fmt::format("{} contacts missing and {} extra against {}", missing, extra,
                                    to_string(kReferenceVariant));
        }
      }
    } catch (const InputError& e) {
      run = failed_run(parameters, e.what());
    } catch (const std::bad_alloc&) {
      run = failed_run(parameters, "out of memory");
    }
    measured.insert(key);
    if (experiment.rounds > 1 && run.status != RunStatus::kFailed) {
      run.samples.round.emplace(run.samples.total_s.size(), round);
    }
    if (first_visit) {
      record_of[key] = result.runs.size();
      result.runs.push_back(std::move(run));
    } else if (run.status == RunStatus::kFailed) {
      result.runs[existing->second] = std::move(run);  // the point is tried again on --resume
    } else {
      add_visit(result.runs[existing->second], run, round);
    }
    write_result_file(options.out, result);  // after every visit: an interruption loses nothing
  }
  for (const std::string& key : measured) {
    switch (result.runs[record_of.at(key)].status) {
      case RunStatus::kOk:
        ++summary.ok;
        break;
      case RunStatus::kInvalid:
        ++summary.invalid;
        break;
      case RunStatus::kFailed:
        ++summary.failed;
        break;
    }
  }
  if (bar) fmt::print(stderr, "\r\033[K");
  summary.seconds = omp_get_wtime() - start;
  return summary;
}

}  // namespace contactlab::tuner
