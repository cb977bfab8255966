// One detection measurement: warm-up, timed repetitions (fixed or adaptive), T_s and T_c
// apart, each thread's busy time and the load imbalance, counters from PAPI. What the detect
// command, the sweeps and the tuner call.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "contactlab/kernels/detector.hpp"
#include "contactlab/kernels/scene.hpp"
#include "contactlab/tuner/papi_counters.hpp"
#include "contactlab/tuner/result_schema.hpp"

namespace contactlab::tuner {

struct MeasureOptions {
  RepetitionPolicy repetition;
  // Counted in one extra run after the timed ones, so that creating and starting event sets
  // never enters the timed samples. Not owned. Usually PapiCounters; any backend works.
  ThreadCounters* papi = nullptr;
  // The status is "invalid" when the contact count differs from this (or between repetitions).
  std::optional<std::uint64_t> expected_contact_pairs;
};

// Runs the measurement with `detector` (its buffers persist, so repetitions time the work and
// not the allocator). The convergence test of adaptive repetition is on T_ALL = T_s + T_c.
// Throws InputError for invalid options or scene (nothing is measured then).
RunRecord measure_detection(ContactDetector& detector, const Scene& scene,
                            const SceneRecord& scene_record, const DetectOptions& options,
                            const MeasureOptions& measure);

// Adds a later visit of the same point (a sweep's next round) to its record: the samples
// appended, their rounds kept (the record's first visit is round 0 unless it says otherwise),
// the summaries taken over all of them. The record becomes invalid when the visit is, or when
// its contact count differs from the record's.
void add_visit(RunRecord& record, const RunRecord& visit, int round);

// The record of a run that could not be made: status failed, the message, no aggregates.
RunRecord failed_run(RunParameters parameters, std::string message);

}  // namespace contactlab::tuner
