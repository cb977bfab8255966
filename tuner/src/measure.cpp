#include "contactlab/tuner/measure.hpp"

#include <fmt/core.h>
#include <omp.h>

#include <algorithm>
#include <vector>

#include "contactlab/kernels/error.hpp"

namespace contactlab::tuner {
namespace {

// The summaries of the samples, and the phases named after them (result_schema.hpp).
void summarize_samples(RunRecord& record, double level) {
  const RunSamples& s = record.samples;
  RunAggregates& a = *record.aggregates;
  a.setup_s = summarize(s.setup_s, level);
  a.detect_s = summarize(s.detect_s, level);
  a.total_s = summarize(s.total_s, level);
  a.imbalance = summarize(s.imbalance, level);
  a.thread_busy_median_s.clear();
  std::size_t threads = 0;
  for (const auto& rep : s.thread_busy_s) threads = std::max(threads, rep.size());
  for (std::size_t t = 0; t < threads; ++t) {
    std::vector<double> busy;
    for (const auto& rep : s.thread_busy_s) busy.push_back(t < rep.size() ? rep[t] : 0.0);
    a.thread_busy_median_s.push_back(median(busy));
  }
  a.repetitions = static_cast<int>(s.total_s.size());
  record.phases["setup"] = a.setup_s;
  record.phases["detect"] = a.detect_s;
  for (const auto& [name, values] : s.parts_s) record.phases[name] = summarize(values, level);
}

}  // namespace

RunRecord measure_detection(ContactDetector& detector, const Scene& scene,
                            const SceneRecord& scene_record, const DetectOptions& options,
                            const MeasureOptions& measure) {
  validate(measure.repetition);
  DetectOptions timed = options;
  timed.observer = nullptr;

  RunRecord record;
  record.parameters.variant = to_string(options.variant);
  record.parameters.threads = resolve_threads(options.threads);
  record.parameters.scene = scene_record;
  record.parameters.repetition = measure.repetition;

  RunSamples& s = record.samples;
  std::optional<DetectRun> first;
  std::vector<std::uint64_t> contact_counts;
  DetectRun last;
  const RepetitionOutcome outcome = repeat_measurement(
      measure.repetition, [&] { detector.run(scene, timed); },
      [&] {
        last = detector.run(scene, timed);
        s.setup_s.push_back(last.setup_s);
        s.detect_s.push_back(last.detect_s);
        s.total_s.push_back(last.total_s());
        s.thread_busy_s.push_back(last.thread_busy_s);
        s.imbalance.push_back(load_imbalance(last.thread_busy_s));
        const double loop_s =
            last.thread_busy_s.empty()
                ? 0.0
                : *std::max_element(last.thread_busy_s.begin(), last.thread_busy_s.end());
        s.parts_s["registration"].push_back(last.registration_s);
        s.parts_s["reorder"].push_back(last.reorder_s);
        s.parts_s["assembly"].push_back(std::max(0.0, last.detect_s - loop_s));
        contact_counts.push_back(last.contact_pairs);
        return last.total_s();
      });

  if (measure.papi) {
    DetectOptions counted = options;
    counted.observer = measure.papi;
    detector.run(scene, counted);
    record.counters.push_back(measure.papi->record());
  }

  RunAggregates& a = record.aggregates.emplace();
  a.warmup_runs = outcome.warmup_runs;
  a.stop_reason = outcome.stop;
  a.measurement_s = outcome.elapsed_s;
  summarize_samples(record, measure.repetition.level);
  record.parameters.threads = last.threads;
  record.work =
      RunWork{last.candidate_tests, last.contact_pairs, last.max_cell_occupancy, last.grid_dims};
  // The same values by name, as every kernel family reports them (result_schema.hpp).
  record.work_counts = {{"candidate_tests", last.candidate_tests},
                        {"contact_pairs", last.contact_pairs},
                        {"max_cell_occupancy", last.max_cell_occupancy},
                        {"hashed_index", last.hashed_index ? 1u : 0u},
                        {"tiled", last.tiled ? 1u : 0u},
                        {"cell_index_bytes", last.index_bytes}};
  // What the detector keeps after a run (ContactDetector::buffer_bytes): memory per particle,
  // and the reverse entries passed between threads, which may grow with the thread count.
  const ContactDetector::BufferBytes kept = detector.buffer_bytes();
  record.work_counts["detector_bytes"] = kept.total;
  record.work_counts["detector_spill_bytes"] = kept.spill_bytes;

  const auto [lo, hi] = std::minmax_element(contact_counts.begin(), contact_counts.end());
  if (*lo != *hi) {
    record.status = RunStatus::kInvalid;
    record.message = fmt::format("contact count differs between repetitions ({} to {})", *lo, *hi);
  } else if (measure.expected_contact_pairs &&
             *measure.expected_contact_pairs != last.contact_pairs) {
    record.status = RunStatus::kInvalid;
    record.message = fmt::format("{} contact pairs, expected {}", last.contact_pairs,
                                 *measure.expected_contact_pairs);
  }
  return record;
}

void add_visit(RunRecord& record, const RunRecord& visit, int round) {
  if (!record.aggregates || !visit.aggregates || !record.work || !visit.work) {
    throw InputError("add_visit: both runs must be measured (failed runs have no samples)");
  }
  RunSamples& s = record.samples;
  const RunSamples& v = visit.samples;
  if (!s.round) s.round.emplace(s.total_s.size(), 0);
  auto append = [](auto& into, const auto& from) {
    into.insert(into.end(), from.begin(), from.end());
  };
  append(s.setup_s, v.setup_s);
  append(s.detect_s, v.detect_s);
  append(s.total_s, v.total_s);
  append(s.thread_busy_s, v.thread_busy_s);
  append(s.imbalance, v.imbalance);
  // A part that only one side recorded (a file from before parts) is dropped: its entries
  // would no longer line up with the repetitions.
  for (auto it = s.parts_s.begin(); it != s.parts_s.end();) {
    const auto from = v.parts_s.find(it->first);
    if (from == v.parts_s.end() || from->second.size() != v.setup_s.size()) {
      record.phases.erase(it->first);
      it = s.parts_s.erase(it);
    } else {
      append(it->second, from->second);
      ++it;
    }
  }
  s.round->insert(s.round->end(), v.total_s.size(), round);
  RunAggregates& a = *record.aggregates;
  a.warmup_runs += visit.aggregates->warmup_runs;
  a.measurement_s += visit.aggregates->measurement_s;
  summarize_samples(record, record.parameters.repetition.level);
  if (record.status == RunStatus::kOk && visit.status != RunStatus::kOk) {
    record.status = visit.status;
    record.message = fmt::format("round {}: {}", round, visit.message);
  } else if (record.status == RunStatus::kOk &&
             visit.work->contact_pairs != record.work->contact_pairs) {
    record.status = RunStatus::kInvalid;
    record.message = fmt::format("contact count differs between rounds ({} in round {}, {} before)",
                                 visit.work->contact_pairs, round, record.work->contact_pairs);
  }
}

RunRecord failed_run(RunParameters parameters, std::string message) {
  RunRecord record;
  record.status = RunStatus::kFailed;
  record.message = message.empty() ? "failed" : std::move(message);
  record.parameters = std::move(parameters);
  return record;
}

}  // namespace contactlab::tuner
