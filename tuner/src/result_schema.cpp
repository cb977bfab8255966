#include "contactlab/tuner/result_schema.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <tuple>

#include "contactlab/kernels/atomic_file.hpp"
#include "contactlab/tuner/field_table.hpp"
#include "context_tables.hpp"

namespace contactlab::tuner {

using nlohmann::json;

std::string_view to_string(RunStatus status) {
  switch (status) {
    case RunStatus::kOk:
      return "ok";
    case RunStatus::kInvalid:
      return "invalid";
    case RunStatus::kFailed:
      return "failed";
  }
  return "failed";
}

RunStatus parse_run_status(std::string_view text) {
  for (const auto s : {RunStatus::kOk, RunStatus::kInvalid, RunStatus::kFailed}) {
    if (text == to_string(s)) return s;
  }
  throw InputError("unknown run status '" + std::string(text) +
                   "' (expected ok, invalid or failed)");
}

SceneRecord describe_generated_scene(const SceneSpec& spec, const Scene& scene) {
  SceneRecord r;
  r.kind = std::string(to_string(spec.kind));
  r.n = scene.size();
  r.diameter = spec.diameter;
  r.seed = spec.seed;
  r.core = spec.core;
  r.background = spec.background;
  r.blob_radius = spec.blob_radius;
  r.size_ratio = spec.size_ratio;
  r.blob_count = spec.blob_count;
  r.box = {scene.box.lo[0], scene.box.lo[1], scene.box.lo[2],
           scene.box.hi[0], scene.box.hi[1], scene.box.hi[2]};
  r.checksum = fmt::format("{:016x}", scene_checksum(scene));
  return r;
}

SceneRecord describe_file_scene(const std::string& path, const Scene& scene, double diameter) {
  SceneRecord r;
  r.kind = "file";
  r.path = path;
  r.n = scene.size();
  if (!scene.has_diameters()) r.diameter = diameter;
  r.box = {scene.box.lo[0], scene.box.lo[1], scene.box.lo[2],
           scene.box.hi[0], scene.box.hi[1], scene.box.hi[2]};
  r.checksum = fmt::format("{:016x}", scene_checksum(scene));
  return r;
}

// ---------------------------------------------------------------------------------------------
// Field tables: each record's JSON names, once, for writing and strict reading alike. Checks
// that involve several fields follow each table as its validate().

namespace {

// A relative half-width is +infinity when the median is 0 and the interval is not a point;
// JSON has no infinity, so it is written as null.
struct InfinityAsNull {
  json encode(double v) const { return std::isfinite(v) ? json(v) : json(nullptr); }
  void decode(const JsonIn& in, double& out) const {
    std::optional<double> v;
    read(in, v);
    out = v.value_or(std::numeric_limits<double>::infinity());
  }
};

void check_schema_version(const JsonIn& at, const int& version) {
  if (version != kSchemaVersion) {
    at.fail(fmt::format("unsupported schema_version {} (this reader knows {})", version,
                        kSchemaVersion));
  }
}

}  // namespace

template <>
struct FieldTable<MedianInterval> {
  using T = MedianInterval;
  static constexpr auto kFields = std::tuple{field("low", &T::low),
                                             field("high", &T::high),
                                             field("lower_rank", &T::lower_rank),
                                             field("upper_rank", &T::upper_rank),
                                             field("coverage", &T::coverage),
                                             field("reached_level", &T::reached_level)};
  static void validate(const JsonIn& in, const T& v) {
    if (v.low > v.high) in.fail("interval low > high");
  }
};

template <>
struct FieldTable<Summary> {
  using T = Summary;
  static constexpr auto kFields =
      std::tuple{field("count", &T::count),
                 field("median", &T::median),
                 field("min", &T::min),
                 field("max", &T::max),
                 field("mean", &T::mean),
                 field("level", &T::level),
                 field("interval", &T::interval),
                 field("relative_half_width", &T::relative_half_width).via(InfinityAsNull{})};
  static void validate(const JsonIn& in, const T& v) {
    if (v.count == 0) in.fail("count must be >= 1");
    if (!(v.min <= v.median && v.median <= v.max)) in.fail("median outside [min, max]");
  }
};

template <>
struct FieldTable<RepetitionPolicy> {
  using T = RepetitionPolicy;
  static constexpr auto kFields =
      std::tuple{field("warmup", &T::warmup),
                 field("repeat", &T::repeat),
                 field("adaptive", &T::adaptive),
                 field("target_relative_half_width", &T::target_relative_half_width),
                 field("time_budget_s", &T::time_budget_s),
                 field("max_repeat", &T::max_repeat),
                 field("level", &T::level)};
  static void validate(const JsonIn& in, const T& v) {
    try {
      contactlab::validate(v);
    } catch (const InputError& e) {
      in.fail(e.what());
    }
  }
};

template <>
struct FieldTable<EventCount> {
  using T = EventCount;
  static constexpr auto kFields = std::tuple{field("name", &T::name), field("total", &T::total),
                                             field("per_thread", &T::per_thread)};
  static void validate(const JsonIn& in, const T& v) {
    if (v.name.empty()) in.fail("event name is empty");
  }
};

template <>
struct FieldTable<CacheLevel> {
  using T = CacheLevel;
  static constexpr auto kFields = std::tuple{
      field("size_bytes", &T::size_bytes), field("associativity", &T::associativity),
      field("line_bytes", &T::line_bytes), computed("sets", &T::sets, "size / (ways * line)")};
};

template <>
struct FieldTable<CacheGeometry> {
  using T = CacheGeometry;
  static constexpr auto kFields =
      std::tuple{field("name", &T::name), field("l1", &T::l1), field("l2", &T::l2),
                 field("description", &T::description), field("approximation", &T::approximation)};
};

template <>
struct FieldTable<SimulationRecord> {
  using T = SimulationRecord;
  // executable and code_isa are absent from results written before the simulated program was
  // built without AVX-512; candidate_tests and simd_target from results written before the
  // simulated program reported them.
  static constexpr auto kFields =
      std::tuple{field("geometry", &T::geometry),
                 field("simulator", &T::simulator),
                 field("threads", &T::threads),
                 field("wall_s", &T::wall_s),
                 field("executable", &T::executable).may_be_absent(),
                 field("code_isa", &T::code_isa).may_be_absent(),
                 field("candidate_tests", &T::candidate_tests).may_be_absent(),
                 field("simd_target", &T::simd_target).may_be_absent()};
};

template <>
struct FieldTable<CounterRecord> {
  using T = CounterRecord;
  static constexpr auto kFields = std::tuple{field("source", &T::source),
                                             field("available", &T::available),
                                             field("reason", &T::reason),
                                             field("l1_miss_percent", &T::l1_miss_percent),
                                             field("l2_miss_percent", &T::l2_miss_percent),
                                             field("l1_formula", &T::l1_formula),
                                             field("l2_formula", &T::l2_formula),
                                             field("region", &T::region),
                                             field("counted_runs", &T::counted_runs),
                                             field("events", &T::events),
                                             field("simulation", &T::simulation),
                                             field("notes", &T::notes)};
  static void validate(const JsonIn& in, const T& v) {
    const bool simulated = v.source.rfind("simulated:", 0) == 0 && v.source.size() > 10;
    if (v.source != "papi" && !simulated) {
      in.fail("source '" + v.source + "' is neither 'papi' nor 'simulated:<geometry>'");
    }
    if (simulated != v.simulation.has_value()) {
      in.fail(simulated ? "a simulated source needs its 'simulation' record"
                        : "'simulation' must be null for source 'papi'");
    }
    if (!v.available) {
      if (v.reason.empty()) in.fail("available is false but no reason is given");
      if (v.l1_miss_percent || v.l2_miss_percent)
        in.fail("miss rates given although available is false");
    }
  }
};

template <>
struct FieldTable<RunParameters> {
  using T = RunParameters;
  static constexpr auto kFields =
      std::tuple{field("variant", &T::variant), field("threads", &T::threads),
                 field("scene", &T::scene), field("repetition", &T::repetition)};
  static void validate(const JsonIn& in, const T& v) {
    if (v.threads < 1) in.fail("threads must be >= 1");
  }
};

template <>
struct FieldTable<RunSamples> {
  using T = RunSamples;
  static constexpr auto kFields = std::tuple{field("setup_s", &T::setup_s),
                                             field("detect_s", &T::detect_s),
                                             field("total_s", &T::total_s),
                                             field("thread_busy_s", &T::thread_busy_s),
                                             field("imbalance", &T::imbalance),
                                             field("round", &T::round).only_when_set(),
                                             field("parts_s", &T::parts_s).may_be_absent()};
  static void validate(const JsonIn& in, const T& v) {
    const std::size_t n = v.setup_s.size();
    if (v.detect_s.size() != n || v.total_s.size() != n || v.thread_busy_s.size() != n ||
        v.imbalance.size() != n || (v.round && v.round->size() != n)) {
      in.fail(
          "setup_s, detect_s, total_s, thread_busy_s, imbalance and round must have one entry per "
          "repetition");
    }
    if (v.round && std::any_of(v.round->begin(), v.round->end(), [](int r) { return r < 0; }))
      in.fail("round: rounds are numbered from 0");
    for (const auto& [name, values] : v.parts_s) {
      if (name.empty()) in.fail("parts_s: a part without a name");
      if (values.size() != n) in.fail("parts_s: " + name + " must have one entry per repetition");
    }
  }
};

template <>
struct FieldTable<RunAggregates> {
  using T = RunAggregates;
  static constexpr auto kFields =
      std::tuple{field("setup_s", &T::setup_s),
                 field("detect_s", &T::detect_s),
                 field("total_s", &T::total_s),
                 field("imbalance", &T::imbalance),
                 field("thread_busy_median_s", &T::thread_busy_median_s),
                 field("repetitions", &T::repetitions),
                 field("warmup_runs", &T::warmup_runs),
                 field("stop_reason", &T::stop_reason).via(EnumCodec<&parse_stop_reason>{}),
                 field("measurement_s", &T::measurement_s)};
};

template <>
struct FieldTable<RunWork> {
  using T = RunWork;
  static constexpr auto kFields = std::tuple{
      field("candidate_tests", &T::candidate_tests), field("contact_pairs", &T::contact_pairs),
      field("max_cell_occupancy", &T::max_cell_occupancy), field("grid", &T::grid)};
};

template <>
struct FieldTable<ContactCheck> {
  using T = ContactCheck;
  static constexpr auto kFields =
      std::tuple{field("reference", &T::reference), field("missing_pairs", &T::missing_pairs),
                 field("extra_pairs", &T::extra_pairs)};
};

template <>
struct FieldTable<MpiRankRecord> {
  using T = MpiRankRecord;
  static constexpr auto kFields = std::tuple{
      field("rank", &T::rank),
      field("threads", &T::threads),
      group("phases_s", field("read", &T::read_s), field("exchange", &T::exchange_s),
            field("registration", &T::registration_s), field("detection", &T::detection_s),
            field("output", &T::output_s), field("total", &T::total_s)),
      field("owned_particles", &T::owned_particles),
      field("halo_particles", &T::halo_particles),
      field("halo_sent", &T::halo_sent),
      field("halo_bytes", &T::halo_bytes),
      field("migrated_in", &T::migrated_in),
      field("candidate_tests", &T::candidate_tests),
      field("contact_pairs", &T::contact_pairs),
      field("peak_rss_bytes", &T::peak_rss_bytes)};
};

template <>
struct FieldTable<MpiRecord> {
  using T = MpiRecord;
  static constexpr auto kFields = std::tuple{field("mode", &T::mode),
                                             field("ranks", &T::ranks),
                                             field("block", &T::block),
                                             field("halo_width", &T::halo_width),
                                             field("work_imbalance", &T::work_imbalance),
                                             field("max_peak_rss_bytes", &T::max_peak_rss_bytes),
                                             field("per_rank", &T::per_rank)};
  static void validate(const JsonIn& in, const T& v) {
    if (v.mode != "replicated" && v.mode != "decomposed")
      in.fail("mode must be replicated or decomposed, got '" + v.mode + "'");
    if (v.ranks < 1 || static_cast<std::size_t>(v.ranks) != v.per_rank.size())
      in.fail("ranks does not match the number of per_rank entries");
  }
};

template <>
struct FieldTable<RunRecord> {
  using T = RunRecord;
  // phases and work_counts came later: files written before them read with both empty.
  static constexpr auto kFields =
      std::tuple{field("status", &T::status).via(EnumCodec<&parse_run_status>{}),
                 field("message", &T::message),
                 field("parameters", &T::parameters),
                 field("samples", &T::samples),
                 field("aggregates", &T::aggregates),
                 field("work", &T::work),
                 field("counters", &T::counters),
                 field("contact_check", &T::contact_check),
                 field("phases", &T::phases).may_be_absent(),
                 field("work_counts", &T::work_counts).may_be_absent(),
                 field("mpi", &T::mpi).only_when_set()};
  static void validate(const JsonIn& in, const T& v) {
    const std::string status(to_string(v.status));
    if (v.status != RunStatus::kFailed) {
      if (!v.aggregates || !v.work)
        in.fail("a run with status '" + status + "' needs aggregates and work");
      if (static_cast<std::size_t>(v.aggregates->repetitions) != v.samples.total_s.size()) {
        in.fail("aggregates.repetitions does not match the number of samples");
      }
    }
    if (v.status != RunStatus::kOk && v.message.empty()) {
      in.fail("a run with status '" + status + "' needs a message");
    }
    if (v.phases.count("") || v.work_counts.count("")) in.fail("a phase or count without a name");
  }
};

template <>
struct FieldTable<ResultFile> {
  using T = ResultFile;
  // The version is checked before the rest is read: another version may name fields otherwise.
  static constexpr auto kFields =
      std::tuple{field("schema_version", &T::schema_version).checked(&check_schema_version),
                 field("context", &T::context), field("runs", &T::runs)};
};

// The public entry points: writing and strict reading, both from the tables above.
void to_json(json& j, const CounterRecord& v) { j = to_json_value(v); }
void to_json(json& j, const Context& v) { j = to_json_value(v); }
void to_json(json& j, const SceneRecord& v) { j = to_json_value(v); }
void to_json(json& j, const RunRecord& v) { j = to_json_value(v); }
void to_json(json& j, const ResultFile& v) { j = to_json_value(v); }

void read(const JsonIn& in, EventCount& out) { read_record(in, out); }
void read(const JsonIn& in, CacheLevel& out) { read_record(in, out); }
void read(const JsonIn& in, CacheGeometry& out) { read_record(in, out); }
void read(const JsonIn& in, SimulationRecord& out) { read_record(in, out); }
void read(const JsonIn& in, CounterRecord& out) { read_record(in, out); }
void read(const JsonIn& in, CacheInfo& out) { read_record(in, out); }
void read(const JsonIn& in, MachineInfo& out) { read_record(in, out); }
void read(const JsonIn& in, BuildRecord& out) { read_record(in, out); }
void read(const JsonIn& in, OpenMpInfo& out) { read_record(in, out); }
void read(const JsonIn& in, PapiEventProbe& out) { read_record(in, out); }
void read(const JsonIn& in, PapiContext& out) { read_record(in, out); }
void read(const JsonIn& in, Context& out) { read_record(in, out); }
void read(const JsonIn& in, SceneRecord& out) { read_record(in, out); }
void read(const JsonIn& in, RunParameters& out) { read_record(in, out); }
void read(const JsonIn& in, RunSamples& out) { read_record(in, out); }
void read(const JsonIn& in, RunAggregates& out) { read_record(in, out); }
void read(const JsonIn& in, RunWork& out) { read_record(in, out); }
void read(const JsonIn& in, ContactCheck& out) { read_record(in, out); }
void read(const JsonIn& in, MpiRankRecord& out) { read_record(in, out); }
void read(const JsonIn& in, MpiRecord& out) { read_record(in, out); }
void read(const JsonIn& in, RunRecord& out) { read_record(in, out); }
void read(const JsonIn& in, ResultFile& out) { read_record(in, out); }

void from_json(const json& j, ResultFile& out) { read(JsonIn(j, "$"), out); }
void from_json(const json& j, RunRecord& out) { read(JsonIn(j, "$"), out); }

ResultFile parse_result(const json& j) {
  ResultFile r;
  read(JsonIn(j, "$"), r);
  return r;
}

ResultFile read_result_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot open: " + std::strerror(errno));
  json j;
  try {
    j = json::parse(in);
  } catch (const json::parse_error& e) {
    throw InputError(path + ": not valid JSON: " + e.what());
  }
  try {
    return parse_result(j);
  } catch (const SchemaError& e) {
    throw SchemaError(path + ": " + e.what());
  }
}

void write_result_file(const std::string& path, const ResultFile& result) {
  const json j = result;
  write_file_atomically(path, [&](std::ostream& out) { out << j.dump(2) << '\n'; });
}

}  // namespace contactlab::tuner

namespace contactlab {

void to_json(nlohmann::json& j, const Summary& v) { j = tuner::to_json_value(v); }
void read(const JsonIn& in, Summary& out) { tuner::read_record(in, out); }
void read(const JsonIn& in, MedianInterval& out) { tuner::read_record(in, out); }
void read(const JsonIn& in, RepetitionPolicy& out) { tuner::read_record(in, out); }

}  // namespace contactlab
