// The field tables of the records that more than one source file's tables hold (the run
// context and the scene: in the result file and in the tune report). field_table.hpp's generic
// functions must see a record's table in every file that instantiates them for it, else one
// template would mean two things (a record written through its table in one file, through its
// to_json in another): each such file includes this header.
#pragma once

#include <string>
#include <tuple>

#include "contactlab/kernels/error.hpp"
#include "contactlab/kernels/scene_generate.hpp"
#include "contactlab/tuner/field_table.hpp"
#include "contactlab/tuner/result_schema.hpp"

namespace contactlab::tuner {

template <>
struct FieldTable<CacheInfo> {
  using T = CacheInfo;
  static constexpr auto kFields = std::tuple{field("level", &T::level),
                                             field("type", &T::type),
                                             field("size_bytes", &T::size_bytes),
                                             field("line_bytes", &T::line_bytes),
                                             field("associativity", &T::associativity),
                                             field("instances", &T::instances),
                                             field("pus_per_instance", &T::pus_per_instance)};
};

template <>
struct FieldTable<MachineInfo> {
  using T = MachineInfo;
  static constexpr auto kFields =
      std::tuple{field("hostname", &T::hostname), field("cpu_model", &T::cpu_model),
                 field("packages", &T::packages), field("cores", &T::cores),
                 field("pus", &T::pus),           field("numa_nodes", &T::numa_nodes),
                 field("caches", &T::caches),     field("topology_source", &T::topology_source)};
};

template <>
struct FieldTable<BuildRecord> {
  using T = BuildRecord;
  static constexpr auto kFields =
      std::tuple{field("version", &T::version),    field("compiler", &T::compiler),
                 field("flags", &T::flags),        field("build_type", &T::build_type),
                 field("native", &T::native),      field("git_commit", &T::git_commit),
                 field("git_dirty", &T::git_dirty)};
};

template <>
struct FieldTable<OpenMpInfo> {
  using T = OpenMpInfo;
  static constexpr auto kFields =
      std::tuple{field("threads", &T::threads),
                 field("max_threads", &T::max_threads),
                 field("num_procs", &T::num_procs),
                 field("version", &T::version),
                 field("proc_bind", &T::proc_bind),
                 field("places", &T::places),
                 field("dynamic", &T::dynamic),
                 field("default_schedule", &T::default_schedule),
                 group("env", field("OMP_NUM_THREADS", &T::env_num_threads),
                       field("OMP_PROC_BIND", &T::env_proc_bind),
                       field("OMP_PLACES", &T::env_places), field("OMP_SCHEDULE", &T::env_schedule),
                       field("OMP_WAIT_POLICY", &T::env_wait_policy))};
};

template <>
struct FieldTable<PapiEventProbe> {
  using T = PapiEventProbe;
  static constexpr auto kFields =
      std::tuple{field("name", &T::name), field("usable", &T::usable), field("reason", &T::reason)};
};

template <>
struct FieldTable<PapiContext> {
  using T = PapiContext;
  static constexpr auto kFields = std::tuple{field("built_with_papi", &T::built_with_papi),
                                             field("initialized", &T::initialized),
                                             field("version", &T::version),
                                             field("error", &T::error),
                                             field("hardware_counters", &T::hardware_counters),
                                             field("components", &T::components),
                                             field("presets_listed", &T::presets_listed),
                                             field("cache_events", &T::cache_events)};
};

template <>
struct FieldTable<Context> {
  using T = Context;
  static constexpr auto kFields = std::tuple{field("machine", &T::machine),
                                             field("build", &T::build),
                                             field("openmp", &T::openmp),
                                             field("mpi_ranks", &T::mpi_ranks),
                                             field("simd_target", &T::simd_target).may_be_absent(),
                                             field("papi", &T::papi),
                                             field("date_utc", &T::date_utc),
                                             field("command_line", &T::command_line),
                                             field("warnings", &T::warnings)};
};

template <>
struct FieldTable<SceneRecord> {
  using T = SceneRecord;
  static constexpr auto kFields = std::tuple{field("kind", &T::kind),
                                             field("path", &T::path),
                                             field("n", &T::n),
                                             field("diameter", &T::diameter),
                                             field("seed", &T::seed),
                                             field("core", &T::core),
                                             field("background", &T::background),
                                             field("blob_radius", &T::blob_radius),
                                             field("size_ratio", &T::size_ratio),
                                             field("blob_count", &T::blob_count),
                                             field("box", &T::box),
                                             field("checksum", &T::checksum)};
  static void validate(const JsonIn& in, const T& v) {
    if (v.kind == "file" && !v.path) in.fail("a file scene needs its 'path'");
    if (v.kind != "file") {
      try {
        parse_scene_kind(v.kind);
      } catch (const InputError& e) {
        in.fail(std::string("kind: ") + e.what());
      }
    }
  }
};

}  // namespace contactlab::tuner
