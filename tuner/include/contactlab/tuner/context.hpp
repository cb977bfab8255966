// The context of a result file: the machine, the build, the OpenMP settings in force, PAPI,
// the date and the command line, with warnings about settings that make timings unreliable.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "contactlab/tuner/papi_counters.hpp"

namespace contactlab::tuner {

struct CacheInfo {
  int level = 0;
  std::string type;  // data, instruction, unified
  std::uint64_t size_bytes = 0;
  int line_bytes = 0;
  int associativity = 0;  // 0 unknown, -1 fully associative
  int instances = 0;
  int pus_per_instance = 0;  // logical CPUs sharing one instance
};

struct MachineInfo {
  std::string hostname;
  std::string cpu_model;
  int packages = 0;
  int cores = 0;
  int pus = 0;  // logical CPUs
  int numa_nodes = 0;
  std::vector<CacheInfo> caches;
  std::string topology_source;  // "hwloc 2.9.0" or "sysfs"
};

// Read once per process (hwloc when built with it, else sysfs and /proc/cpuinfo).
const MachineInfo& machine_info();

struct BuildRecord {
  std::string version;
  std::string compiler;
  std::string flags;
  std::string build_type;
  bool native = false;
  std::string git_commit;
  bool git_dirty = false;
};
BuildRecord build_record();

struct OpenMpInfo {
  int threads = 0;        // threads the runs use
  int max_threads = 0;    // omp_get_max_threads()
  int num_procs = 0;      // omp_get_num_procs()
  int version = 0;        // _OPENMP
  std::string proc_bind;  // omp_get_proc_bind(): false, true, primary, close, spread
  int places = 0;         // omp_get_num_places()
  bool dynamic = false;
  std::string default_schedule;  // omp_get_schedule() before any run (runs set the variant's)
  // The environment as given (null = unset).
  std::optional<std::string> env_num_threads, env_proc_bind, env_places, env_schedule,
      env_wait_policy;
};

struct PapiContext {
  bool built_with_papi = false;
  bool initialized = false;
  std::string version;
  std::string error;
  int hardware_counters = 0;
  std::vector<std::string> components;
  std::vector<std::string> presets_listed;
  std::vector<PapiEventProbe> cache_events;
};

struct Context {
  MachineInfo machine;
  BuildRecord build;
  OpenMpInfo openmp;
  int mpi_ranks = 1;
  // The SIMD target of the sorted layouts' contact tests (contactlab/kernels/simd.hpp): the
  // best the CPU offers unless CONTACTLAB_SIMD chose another. Absent in files written before.
  std::string simd_target;
  PapiContext papi;
  std::string date_utc;  // ISO 8601
  std::string command_line;
  std::vector<std::string> warnings;
};

// `threads` = the thread count the runs will use (0 = OpenMP's default).
Context collect_context(const std::string& command_line, int threads);

// Unbound threads, more threads than cores, a build that is not Release.
std::vector<std::string> context_warnings(const Context& context);

}  // namespace contactlab::tuner
