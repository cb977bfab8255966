// The thread emulation's result document (docs/emulation.md): the method in words, the measured
// and emulated points, and the checks of the emulation against the measurements.
#include <fmt/core.h>
#include <fmt/ranges.h>

#include "contactlab/tuner/thread_emulation.hpp"
#include "contactlab/tuner_model/emulation.hpp"

namespace contactlab::tuner {

nlohmann::json interval_json(const Summary& s) {
  return {{"median", s.median},
          {"low", s.interval.low},
          {"high", s.interval.high},
          {"level", s.level},
          {"repetitions", s.count}};
}

nlohmann::json emulation_document(const ThreadEmulation& emulation,
                                  const ThreadEmulationOptions& options, const Context& context,
                                  const SceneRecord& scene) {
  nlohmann::json doc;
  doc["schema_version"] = 1;
  doc["kind"] = "contactlab-thread-emulation";
  doc["label"] = "emulated";
  doc["context"] = context;
  doc["scene"] = scene;
  // Named: the bandwidth sentence once came in the place of "{most}" (arguments out of order).
  doc["method"] = fmt::format(
      "Measured here: every variant at {measured} thread(s), {rounds} interleaved rounds "
      "(medians with 95% order-statistic intervals). Emulated: the detection loop's exact work "
      "per iteration priced by machine costs calibrated on small calibration scenes (not this "
      "one) at up to {calibrated} threads, scaled so that the one-thread replay equals this "
      "scene's measured one-thread T_c less its output copy, then replayed under the variant's "
      "schedule as libgomp deals it (static, static,k, dynamic,k, guided,k) or as the balanced "
      "blocks, after each thread's weighing of its slice at the seconds per weighed iteration "
      "measured at the most threads; a deal in chunks (static,k and dynamic,k) at P threads has "
      "its loop scaled by a locality factor measured here: thread 0's share of static,k at P "
      "threads timed alone at one thread, less a run with no block, over its replay (the caches "
      "and blocks of homes a thread loses by jumping between chunks); plus the rows the "
      "schedule leaves to copy after the loop at P threads (the calibrated cost per output "
      "entry); plus the rest of the assembly after the loop (row offsets, the half stencil's "
      "reverse entries) = serial + parallel/P fitted from its measured 1- and {most}-thread "
      "times less the copy, or, for the half stencil under a deal whose threads pass their "
      "reverse entries on to the rows' owners (chunks, dynamic, guided, unsorted), work/P + "
      "exchange (P-1)/P^2 fitted from the same two times; T_s = serial + parallel/P fitted from "
      "the measured 1- and "
      "{most}-thread T_s. {bandwidth}Not modelled: shared caches as threads are added, and "
      "caches that the split work comes to fit (superlinear speed-up).",
      fmt::arg("measured", fmt::join(options.measured_threads, ", ")),
      fmt::arg("rounds", options.rounds), fmt::arg("calibrated", emulation.calibration.threads),
      fmt::arg("most",
               *std::max_element(options.measured_threads.begin(), options.measured_threads.end())),
      fmt::arg("bandwidth",
               options.memory
                   ? "Bandwidth (the machine file in `bandwidth`): every phase (setup, loop, the "
                     "rows after it) takes at least its bytes, counted from the exact work and "
                     "the data layout, over the bandwidth its threads draw: the probe's at the "
                     "thread counts it measured, beyond them a saturating curve towards the "
                     "stated ceiling. "
                   : "Not modelled: memory bandwidth (no machine file): beyond this machine's "
                     "cores an emulated speed-up is what the schedule's balance allows. "));
  doc["measured_threads"] = options.measured_threads;
  doc["bandwidth"] = options.memory ? options.memory->json() : nlohmann::json(nullptr);
  nlohmann::json calibration = nlohmann::json::object();
  for (const auto& [key, s] : emulation.calibration.structures) {
    calibration[key] = {{"runs", s.runs}, {"rms_relative_error", s.rms_relative_error}};
  }
  doc["calibration"] = {{"threads", emulation.calibration.threads},
                        {"source", emulation.calibration.source},
                        {"seconds", emulation.calibration.seconds},
                        {"structures", calibration}};
  doc["variants"] = nlohmann::json::array();
  for (const VariantEmulation& e : emulation.variants) {
    nlohmann::json v{{"variant", to_string(e.variant)}, {"anchor_scale", e.anchor_scale}};
    if (options.memory) {
      const DetectionTraffic& t = e.traffic;
      v["traffic"] = {{"setup_bytes", t.setup_bytes},
                      {"loop_bytes", t.loop_bytes},
                      {"rows_bytes", t.rows_bytes},
                      {"offsets_bytes", t.offsets_bytes},
                      {"footprint_bytes", t.footprint_bytes},
                      {"working_set_bytes", options.memory->working_set(t.footprint_bytes).bytes}};
    }
    v["measured"] = nlohmann::json::array();
    for (const MeasuredThreads& m : e.measured) {
      v["measured"].push_back({{"threads", m.threads},
                               {"setup_s", interval_json(m.setup_s)},
                               {"detect_s", interval_json(m.detect_s)},
                               {"total_s", interval_json(m.total_s)},
                               {"repetitions", m.total_s.count}});
    }
    v["emulated"] = nlohmann::json::array();
    for (const EmulatedThreads& p : e.emulated) {
      nlohmann::json point{
          {"threads", p.threads},   {"setup_s", p.setup_s},       {"detect_s", p.detect_s},
          {"total_s", p.total_s()}, {"speedup", p.speedup},       {"imbalance", p.imbalance},
          {"output_s", p.output_s}, {"assembly_s", p.assembly_s}, {"locality_factor", p.locality}};
      if (options.memory) {
        point["bytes_per_s"] = p.bytes_per_s;
        point["memory_s"] = p.memory_s;
      }
      v["emulated"].push_back(std::move(point));
    }
    v["validation"] = nlohmann::json::array();
    for (const EmulationCheck& c : e.checks) {
      v["validation"].push_back(
          {{"threads", c.threads},
           {"measured_total_s", c.measured_total_s},
           {"emulated_total_s", c.emulated_total_s},
           {"relative_error", relative_error(c.emulated_total_s, c.measured_total_s)},
           {"measured_detect_s", c.measured_detect_s},
           {"emulated_detect_s", c.emulated_detect_s},
           {"detect_relative_error", relative_error(c.emulated_detect_s, c.measured_detect_s)}});
    }
    doc["variants"].push_back(std::move(v));
  }
  doc["chunk_study"] = nlohmann::json::array();
  for (const EmulatedChunkStudy& s : emulation.chunk_study) {
    nlohmann::json points = nlohmann::json::array();
    for (std::size_t k = 0; k < s.detect_s.size(); ++k) {
      points.push_back({{"chunk", s.detect_s[k].first},
                        {"detect_s", s.detect_s[k].second},
                        {"locality_factor", s.locality[k].second}});
    }
    nlohmann::json classic = nlohmann::json::array();
    for (const EmulatedChunkStudy::Classic& c : s.classic) {
      classic.push_back({{"name", c.name}, {"chunk", c.chunk}, {"detect_s", c.detect_s}});
    }
    const std::string name = to_string(s.variant);
    doc["chunk_study"].push_back({{"threads", s.threads},
                                  {"variant", name.substr(0, name.rfind(',')) + ",k"},
                                  {"schedule", std::string(to_string(s.variant.schedule.kind))},
                                  {"points", points},
                                  {"best_chunk", s.best_chunk},
                                  {"best_detect_s", s.best_detect_s},
                                  {"block_detect_s", s.block_detect_s},
                                  {"classic", classic}});
  }
  return doc;
}

}  // namespace contactlab::tuner
