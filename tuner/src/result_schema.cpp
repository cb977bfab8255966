#include "contactlab/tuner/result_schema.hpp"

#include <fmt/core.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>

#include "contactlab/kernels/atomic_file.hpp"

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
// Writing

namespace {

json finite_or_null(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

json to_json_value(const MedianInterval& v) {
  return {{"low", v.low},
          {"high", v.high},
          {"lower_rank", v.lower_rank},
          {"upper_rank", v.upper_rank},
          {"coverage", v.coverage},
          {"reached_level", v.reached_level}};
}

json to_json_value(const RepetitionPolicy& v) {
  return {{"warmup", v.warmup},
          {"repeat", v.repeat},
          {"adaptive", v.adaptive},
          {"target_relative_half_width", v.target_relative_half_width},
          {"time_budget_s", v.time_budget_s},
          {"max_repeat", v.max_repeat},
          {"level", v.level}};
}

json to_json_value(const CacheLevel& v) {
  return {{"size_bytes", v.size_bytes},
          {"associativity", v.associativity},
          {"line_bytes", v.line_bytes},
          {"sets", v.sets()}};
}

json to_json_value(const CacheGeometry& v) {
  return {{"name", v.name},
          {"l1", to_json_value(v.l1)},
          {"l2", to_json_value(v.l2)},
          {"description", v.description},
          {"approximation", v.approximation}};
}

json to_json_value(const SimulationRecord& v) {
  return {{"geometry", to_json_value(v.geometry)},
          {"simulator", v.simulator},
          {"threads", v.threads},
          {"wall_s", v.wall_s},
          {"executable", v.executable},
          {"code_isa", v.code_isa}};
}

json to_json_value(const EventCount& v) {
  return {{"name", v.name}, {"total", v.total}, {"per_thread", v.per_thread}};
}

json to_json_value(const CacheInfo& v) {
  return {{"level", v.level},
          {"type", v.type},
          {"size_bytes", v.size_bytes},
          {"line_bytes", v.line_bytes},
          {"associativity", v.associativity},
          {"instances", v.instances},
          {"pus_per_instance", v.pus_per_instance}};
}

json to_json_value(const RunParameters& v) {
  return {{"variant", v.variant},
          {"threads", v.threads},
          {"scene", v.scene},
          {"repetition", to_json_value(v.repetition)}};
}

json to_json_value(const RunSamples& v) {
  return {{"setup_s", v.setup_s},
          {"detect_s", v.detect_s},
          {"total_s", v.total_s},
          {"thread_busy_s", v.thread_busy_s},
          {"imbalance", v.imbalance}};
}

json to_json_value(const RunAggregates& v) {
  return {{"setup_s", v.setup_s},
          {"detect_s", v.detect_s},
          {"total_s", v.total_s},
          {"imbalance", v.imbalance},
          {"thread_busy_median_s", v.thread_busy_median_s},
          {"repetitions", v.repetitions},
          {"warmup_runs", v.warmup_runs},
          {"stop_reason", to_string(v.stop_reason)},
          {"measurement_s", v.measurement_s}};
}

json to_json_value(const RunWork& v) {
  return {{"candidate_tests", v.candidate_tests},
          {"contact_pairs", v.contact_pairs},
          {"max_cell_occupancy", v.max_cell_occupancy},
          {"grid", v.grid}};
}

}  // namespace

void to_json(json& j, const Summary& v) {
  j = {{"count", v.count},
       {"median", v.median},
       {"min", v.min},
       {"max", v.max},
       {"mean", v.mean},
       {"level", v.level},
       {"interval", to_json_value(v.interval)},
       {"relative_half_width", finite_or_null(v.relative_half_width)}};
}

void to_json(json& j, const CounterRecord& v) {
  json events = json::array();
  for (const auto& e : v.events) events.push_back(to_json_value(e));
  j = {{"source", v.source},
       {"available", v.available},
       {"reason", v.reason},
       {"l1_miss_percent", optional_json(v.l1_miss_percent)},
       {"l2_miss_percent", optional_json(v.l2_miss_percent)},
       {"l1_formula", v.l1_formula},
       {"l2_formula", v.l2_formula},
       {"region", v.region},
       {"counted_runs", v.counted_runs},
       {"events", events},
       {"simulation", v.simulation ? to_json_value(*v.simulation) : json(nullptr)},
       {"notes", v.notes}};
}

void to_json(json& j, const Context& v) {
  json caches = json::array();
  for (const auto& c : v.machine.caches) caches.push_back(to_json_value(c));
  json probes = json::array();
  for (const auto& p : v.papi.cache_events) {
    probes.push_back({{"name", p.name}, {"usable", p.usable}, {"reason", p.reason}});
  }
  const OpenMpInfo& o = v.openmp;
  j = {{"machine",
        {{"hostname", v.machine.hostname},
         {"cpu_model", v.machine.cpu_model},
         {"packages", v.machine.packages},
         {"cores", v.machine.cores},
         {"pus", v.machine.pus},
         {"numa_nodes", v.machine.numa_nodes},
         {"caches", caches},
         {"topology_source", v.machine.topology_source}}},
       {"build",
        {{"version", v.build.version},
         {"compiler", v.build.compiler},
         {"flags", v.build.flags},
         {"build_type", v.build.build_type},
         {"native", v.build.native},
         {"git_commit", v.build.git_commit},
         {"git_dirty", v.build.git_dirty}}},
       {"openmp",
        {{"threads", o.threads},
         {"max_threads", o.max_threads},
         {"num_procs", o.num_procs},
         {"version", o.version},
         {"proc_bind", o.proc_bind},
         {"places", o.places},
         {"dynamic", o.dynamic},
         {"default_schedule", o.default_schedule},
         {"env",
          {{"OMP_NUM_THREADS", optional_json(o.env_num_threads)},
           {"OMP_PROC_BIND", optional_json(o.env_proc_bind)},
           {"OMP_PLACES", optional_json(o.env_places)},
           {"OMP_SCHEDULE", optional_json(o.env_schedule)},
           {"OMP_WAIT_POLICY", optional_json(o.env_wait_policy)}}}}},
       {"mpi_ranks", v.mpi_ranks},
       {"papi",
        {{"built_with_papi", v.papi.built_with_papi},
         {"initialized", v.papi.initialized},
         {"version", v.papi.version},
         {"error", v.papi.error},
         {"hardware_counters", v.papi.hardware_counters},
         {"components", v.papi.components},
         {"presets_listed", v.papi.presets_listed},
         {"cache_events", probes}}},
       {"date_utc", v.date_utc},
       {"command_line", v.command_line},
       {"warnings", v.warnings}};
}

void to_json(json& j, const SceneRecord& v) {
  j = {{"kind", v.kind},
       {"path", optional_json(v.path)},
       {"n", v.n},
       {"diameter", optional_json(v.diameter)},
       {"seed", optional_json(v.seed)},
       {"core", optional_json(v.core)},
       {"background", optional_json(v.background)},
       {"blob_radius", optional_json(v.blob_radius)},
       {"size_ratio", optional_json(v.size_ratio)},
       {"blob_count", optional_json(v.blob_count)},
       {"box", v.box},
       {"checksum", v.checksum}};
}

void to_json(json& j, const RunRecord& v) {
  j = {{"status", to_string(v.status)},
       {"message", v.message},
       {"parameters", to_json_value(v.parameters)},
       {"samples", to_json_value(v.samples)},
       {"aggregates", v.aggregates ? to_json_value(*v.aggregates) : json(nullptr)},
       {"work", v.work ? to_json_value(*v.work) : json(nullptr)},
       {"counters", v.counters},
       {"contact_check", v.contact_check ? json{{"reference", v.contact_check->reference},
                                                {"missing_pairs", v.contact_check->missing_pairs},
                                                {"extra_pairs", v.contact_check->extra_pairs}}
                                         : json(nullptr)}};
}

void to_json(json& j, const ResultFile& v) {
  j = {{"schema_version", v.schema_version}, {"context", v.context}, {"runs", v.runs}};
}

// ---------------------------------------------------------------------------------------------
// Strict reading

void read(const JsonIn& in, MedianInterval& out) {
  ObjectIn o(in);
  o("low", out.low);
  o("high", out.high);
  std::uint64_t lower = 0, upper = 0;
  o("lower_rank", lower);
  o("upper_rank", upper);
  out.lower_rank = lower;
  out.upper_rank = upper;
  o("coverage", out.coverage);
  o("reached_level", out.reached_level);
  o.finish();
  if (out.low > out.high) in.fail("interval low > high");
}

void read(const JsonIn& in, Summary& out) {
  ObjectIn o(in);
  std::uint64_t count = 0;
  o("count", count);
  out.count = count;
  o("median", out.median);
  o("min", out.min);
  o("max", out.max);
  o("mean", out.mean);
  o("level", out.level);
  o("interval", out.interval);
  std::optional<double> relative;
  o("relative_half_width", relative);
  out.relative_half_width = relative.value_or(std::numeric_limits<double>::infinity());
  o.finish();
  if (out.count == 0) in.fail("count must be >= 1");
  if (!(out.min <= out.median && out.median <= out.max)) in.fail("median outside [min, max]");
}

void read(const JsonIn& in, RepetitionPolicy& out) {
  ObjectIn o(in);
  o("warmup", out.warmup);
  o("repeat", out.repeat);
  o("adaptive", out.adaptive);
  o("target_relative_half_width", out.target_relative_half_width);
  o("time_budget_s", out.time_budget_s);
  o("max_repeat", out.max_repeat);
  o("level", out.level);
  o.finish();
  try {
    validate(out);
  } catch (const InputError& e) {
    in.fail(e.what());
  }
}

void read(const JsonIn& in, EventCount& out) {
  ObjectIn o(in);
  o("name", out.name);
  o("total", out.total);
  o("per_thread", out.per_thread);
  o.finish();
  if (out.name.empty()) in.fail("event name is empty");
}

void read(const JsonIn& in, CacheLevel& out) {
  ObjectIn o(in);
  o("size_bytes", out.size_bytes);
  o("associativity", out.associativity);
  o("line_bytes", out.line_bytes);
  std::uint64_t sets = 0;
  o("sets", sets);
  o.finish();
  if (sets != out.sets())
    in.fail(fmt::format("sets = {} does not match size / (ways * line) = {}", sets, out.sets()));
}

void read(const JsonIn& in, CacheGeometry& out) {
  ObjectIn o(in);
  o("name", out.name);
  o("l1", out.l1);
  o("l2", out.l2);
  o("description", out.description);
  o("approximation", out.approximation);
  o.finish();
}

void read(const JsonIn& in, SimulationRecord& out) {
  ObjectIn o(in);
  o("geometry", out.geometry);
  o("simulator", out.simulator);
  o("threads", out.threads);
  o("wall_s", out.wall_s);
  // Absent from results written before the simulated program was built without AVX-512.
  if (const auto e = o.optional_field("executable")) read(*e, out.executable);
  if (const auto c = o.optional_field("code_isa")) read(*c, out.code_isa);
  o.finish();
}

void read(const JsonIn& in, CounterRecord& out) {
  ObjectIn o(in);
  o("source", out.source);
  o("available", out.available);
  o("reason", out.reason);
  o("l1_miss_percent", out.l1_miss_percent);
  o("l2_miss_percent", out.l2_miss_percent);
  o("l1_formula", out.l1_formula);
  o("l2_formula", out.l2_formula);
  o("region", out.region);
  o("counted_runs", out.counted_runs);
  o("events", out.events);
  o("simulation", out.simulation);
  o("notes", out.notes);
  o.finish();
  const bool simulated = out.source.rfind("simulated:", 0) == 0 && out.source.size() > 10;
  if (out.source != "papi" && !simulated) {
    in.fail("source '" + out.source + "' is neither 'papi' nor 'simulated:<geometry>'");
  }
  if (simulated != out.simulation.has_value()) {
    in.fail(simulated ? "a simulated source needs its 'simulation' record"
                      : "'simulation' must be null for source 'papi'");
  }
  if (!out.available) {
    if (out.reason.empty()) in.fail("available is false but no reason is given");
    if (out.l1_miss_percent || out.l2_miss_percent)
      in.fail("miss rates given although available is false");
  }
}

void read(const JsonIn& in, CacheInfo& out) {
  ObjectIn o(in);
  o("level", out.level);
  o("type", out.type);
  o("size_bytes", out.size_bytes);
  o("line_bytes", out.line_bytes);
  o("associativity", out.associativity);
  o("instances", out.instances);
  o("pus_per_instance", out.pus_per_instance);
  o.finish();
}

void read(const JsonIn& in, MachineInfo& out) {
  ObjectIn o(in);
  o("hostname", out.hostname);
  o("cpu_model", out.cpu_model);
  o("packages", out.packages);
  o("cores", out.cores);
  o("pus", out.pus);
  o("numa_nodes", out.numa_nodes);
  o("caches", out.caches);
  o("topology_source", out.topology_source);
  o.finish();
}

void read(const JsonIn& in, BuildRecord& out) {
  ObjectIn o(in);
  o("version", out.version);
  o("compiler", out.compiler);
  o("flags", out.flags);
  o("build_type", out.build_type);
  o("native", out.native);
  o("git_commit", out.git_commit);
  o("git_dirty", out.git_dirty);
  o.finish();
}

void read(const JsonIn& in, OpenMpInfo& out) {
  ObjectIn o(in);
  o("threads", out.threads);
  o("max_threads", out.max_threads);
  o("num_procs", out.num_procs);
  o("version", out.version);
  o("proc_bind", out.proc_bind);
  o("places", out.places);
  o("dynamic", out.dynamic);
  o("default_schedule", out.default_schedule);
  ObjectIn env(o.field("env"));
  env("OMP_NUM_THREADS", out.env_num_threads);
  env("OMP_PROC_BIND", out.env_proc_bind);
  env("OMP_PLACES", out.env_places);
  env("OMP_SCHEDULE", out.env_schedule);
  env("OMP_WAIT_POLICY", out.env_wait_policy);
  env.finish();
  o.finish();
}

void read(const JsonIn& in, PapiEventProbe& out) {
  ObjectIn o(in);
  o("name", out.name);
  o("usable", out.usable);
  o("reason", out.reason);
  o.finish();
}

void read(const JsonIn& in, PapiContext& out) {
  ObjectIn o(in);
  o("built_with_papi", out.built_with_papi);
  o("initialized", out.initialized);
  o("version", out.version);
  o("error", out.error);
  o("hardware_counters", out.hardware_counters);
  o("components", out.components);
  o("presets_listed", out.presets_listed);
  o("cache_events", out.cache_events);
  o.finish();
}

void read(const JsonIn& in, Context& out) {
  ObjectIn o(in);
  o("machine", out.machine);
  o("build", out.build);
  o("openmp", out.openmp);
  o("mpi_ranks", out.mpi_ranks);
  o("papi", out.papi);
  o("date_utc", out.date_utc);
  o("command_line", out.command_line);
  o("warnings", out.warnings);
  o.finish();
}

void read(const JsonIn& in, SceneRecord& out) {
  ObjectIn o(in);
  o("kind", out.kind);
  o("path", out.path);
  o("n", out.n);
  o("diameter", out.diameter);
  o("seed", out.seed);
  o("core", out.core);
  o("background", out.background);
  o("blob_radius", out.blob_radius);
  o("size_ratio", out.size_ratio);
  o("blob_count", out.blob_count);
  o("box", out.box);
  o("checksum", out.checksum);
  o.finish();
  if (out.kind == "file" && !out.path) in.fail("a file scene needs its 'path'");
  if (out.kind != "file") {
    try {
      parse_scene_kind(out.kind);
    } catch (const InputError& e) {
      in.fail(std::string("kind: ") + e.what());
    }
  }
}

void read(const JsonIn& in, RunParameters& out) {
  ObjectIn o(in);
  o("variant", out.variant);
  o("threads", out.threads);
  o("scene", out.scene);
  o("repetition", out.repetition);
  o.finish();
  if (out.threads < 1) in.fail("threads must be >= 1");
}

void read(const JsonIn& in, RunSamples& out) {
  ObjectIn o(in);
  o("setup_s", out.setup_s);
  o("detect_s", out.detect_s);
  o("total_s", out.total_s);
  o("thread_busy_s", out.thread_busy_s);
  o("imbalance", out.imbalance);
  o.finish();
  const std::size_t n = out.setup_s.size();
  if (out.detect_s.size() != n || out.total_s.size() != n || out.thread_busy_s.size() != n ||
      out.imbalance.size() != n) {
    in.fail(
        "setup_s, detect_s, total_s, thread_busy_s and imbalance must have one entry per "
        "repetition");
  }
}

void read(const JsonIn& in, RunAggregates& out) {
  ObjectIn o(in);
  o("setup_s", out.setup_s);
  o("detect_s", out.detect_s);
  o("total_s", out.total_s);
  o("imbalance", out.imbalance);
  o("thread_busy_median_s", out.thread_busy_median_s);
  o("repetitions", out.repetitions);
  o("warmup_runs", out.warmup_runs);
  std::string stop;
  o("stop_reason", stop);
  try {
    out.stop_reason = parse_stop_reason(stop);
  } catch (const InputError& e) {
    in.fail(std::string("stop_reason: ") + e.what());
  }
  o("measurement_s", out.measurement_s);
  o.finish();
}

void read(const JsonIn& in, RunWork& out) {
  ObjectIn o(in);
  o("candidate_tests", out.candidate_tests);
  o("contact_pairs", out.contact_pairs);
  o("max_cell_occupancy", out.max_cell_occupancy);
  o("grid", out.grid);
  o.finish();
}

void read(const JsonIn& in, ContactCheck& out) {
  ObjectIn o(in);
  o("reference", out.reference);
  o("missing_pairs", out.missing_pairs);
  o("extra_pairs", out.extra_pairs);
  o.finish();
}

void read(const JsonIn& in, RunRecord& out) {
  ObjectIn o(in);
  std::string status;
  o("status", status);
  try {
    out.status = parse_run_status(status);
  } catch (const InputError& e) {
    in.fail(std::string("status: ") + e.what());
  }
  o("message", out.message);
  o("parameters", out.parameters);
  o("samples", out.samples);
  o("aggregates", out.aggregates);
  o("work", out.work);
  o("counters", out.counters);
  o("contact_check", out.contact_check);
  o.finish();
  if (out.status != RunStatus::kFailed) {
    if (!out.aggregates || !out.work)
      in.fail("a run with status '" + status + "' needs aggregates and work");
    if (static_cast<std::size_t>(out.aggregates->repetitions) != out.samples.total_s.size()) {
      in.fail("aggregates.repetitions does not match the number of samples");
    }
  }
  if (out.status != RunStatus::kOk && out.message.empty()) {
    in.fail("a run with status '" + status + "' needs a message");
  }
}

void read(const JsonIn& in, ResultFile& out) {
  ObjectIn o(in);
  o("schema_version", out.schema_version);
  if (out.schema_version != kSchemaVersion) {
    JsonIn(in.value()["schema_version"], in.path() + ".schema_version")
        .fail(fmt::format("unsupported schema_version {} (this reader knows {})",
                          out.schema_version, kSchemaVersion));
  }
  o("context", out.context);
  o("runs", out.runs);
  o.finish();
}

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
