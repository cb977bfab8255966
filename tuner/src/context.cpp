#include "contactlab/tuner/context.hpp"

#include <fmt/core.h>
#include <omp.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <map>
#include <string_view>

#include "contactlab/kernels/build_info.hpp"
#include "contactlab/kernels/simd.hpp"

#if CONTACTLAB_HAVE_HWLOC
#include <hwloc.h>
#endif

namespace contactlab::tuner {
namespace {

std::optional<std::string> env(const char* name) {
  if (const char* v = std::getenv(name)) return std::string(v);
  return std::nullopt;
}

std::string read_first_line(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  return line;
}

std::string cpuinfo_model() {
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("model name", 0) == 0) {
      const auto colon = line.find(':');
      if (colon != std::string::npos) {
        auto value = line.substr(colon + 1);
        value.erase(0, value.find_first_not_of(" \t"));
        return value;
      }
    }
  }
  return "unknown";
}

// "32K" -> 32768 (sysfs cache sizes).
std::uint64_t parse_sysfs_size(const std::string& text) {
  if (text.empty()) return 0;
  std::uint64_t value = std::strtoull(text.c_str(), nullptr, 10);
  switch (text.back()) {
    case 'K':
      return value << 10;
    case 'M':
      return value << 20;
    case 'G':
      return value << 30;
    default:
      return value;
  }
}

int count_cpus_in_list(const std::string& list) {
  // "0-3,8" -> 5
  int count = 0;
  std::size_t pos = 0;
  while (pos < list.size()) {
    const auto comma = list.find(',', pos);
    const std::string part =
        list.substr(pos, comma == std::string::npos ? std::string::npos : comma - pos);
    const auto dash = part.find('-');
    if (!part.empty()) {
      count += dash == std::string::npos
                   ? 1
                   : std::atoi(part.c_str() + dash + 1) - std::atoi(part.c_str()) + 1;
    }
    if (comma == std::string::npos) break;
    pos = comma + 1;
  }
  return count;
}

MachineInfo sysfs_machine() {
  MachineInfo m;
  m.topology_source = "sysfs";
  m.cpu_model = cpuinfo_model();
  m.pus = static_cast<int>(sysconf(_SC_NPROCESSORS_ONLN));
  // Cores: distinct (package, core) ids.
  std::map<std::pair<int, int>, int> cores;
  std::map<int, int> packages;
  for (int cpu = 0; cpu < m.pus; ++cpu) {
    const std::string base = fmt::format("/sys/devices/system/cpu/cpu{}/topology/", cpu);
    const int package = std::atoi(read_first_line(base + "physical_package_id").c_str());
    const int core = std::atoi(read_first_line(base + "core_id").c_str());
    cores[{package, core}] = 1;
    packages[package] = 1;
  }
  m.cores = std::max<int>(1, static_cast<int>(cores.size()));
  m.packages = std::max<int>(1, static_cast<int>(packages.size()));
  m.numa_nodes = 1;
  for (int index = 0;; ++index) {
    const std::string base = fmt::format("/sys/devices/system/cpu/cpu0/cache/index{}/", index);
    const std::string level = read_first_line(base + "level");
    if (level.empty()) break;
    CacheInfo c;
    c.level = std::atoi(level.c_str());
    std::string type = read_first_line(base + "type");
    std::transform(type.begin(), type.end(), type.begin(),
                   [](unsigned char ch) { return std::tolower(ch); });
    c.type = type;
    c.size_bytes = parse_sysfs_size(read_first_line(base + "size"));
    c.line_bytes = std::atoi(read_first_line(base + "coherency_line_size").c_str());
    c.associativity = std::atoi(read_first_line(base + "ways_of_associativity").c_str());
    c.pus_per_instance = std::max(1, count_cpus_in_list(read_first_line(base + "shared_cpu_list")));
    c.instances = std::max(1, m.pus / c.pus_per_instance);
    m.caches.push_back(c);
  }
  return m;
}

#if CONTACTLAB_HAVE_HWLOC
MachineInfo hwloc_machine() {
  hwloc_topology_t topology;
  if (hwloc_topology_init(&topology) != 0) return sysfs_machine();
  if (hwloc_topology_load(topology) != 0) {
    hwloc_topology_destroy(topology);
    return sysfs_machine();
  }
  MachineInfo m;
  const unsigned api = hwloc_get_api_version();
  m.topology_source = fmt::format("hwloc (API {}.{}.{})", api >> 16, (api >> 8) & 0xff, api & 0xff);
  m.packages = hwloc_get_nbobjs_by_type(topology, HWLOC_OBJ_PACKAGE);
  m.cores = hwloc_get_nbobjs_by_type(topology, HWLOC_OBJ_CORE);
  m.pus = hwloc_get_nbobjs_by_type(topology, HWLOC_OBJ_PU);
  m.numa_nodes = hwloc_get_nbobjs_by_type(topology, HWLOC_OBJ_NUMANODE);
  m.cpu_model = "unknown";
  if (hwloc_obj_t package = hwloc_get_obj_by_type(topology, HWLOC_OBJ_PACKAGE, 0)) {
    if (const char* model = hwloc_obj_get_info_by_name(package, "CPUModel")) m.cpu_model = model;
  }
  if (m.cpu_model == "unknown") m.cpu_model = cpuinfo_model();
  for (const hwloc_obj_type_t type :
       {HWLOC_OBJ_L1CACHE, HWLOC_OBJ_L1ICACHE, HWLOC_OBJ_L2CACHE, HWLOC_OBJ_L2ICACHE,
        HWLOC_OBJ_L3CACHE, HWLOC_OBJ_L3ICACHE, HWLOC_OBJ_L4CACHE, HWLOC_OBJ_L5CACHE}) {
    const int count = hwloc_get_nbobjs_by_type(topology, type);
    if (count <= 0) continue;
    const hwloc_obj_t obj = hwloc_get_obj_by_type(topology, type, 0);
    const auto& attr = obj->attr->cache;
    CacheInfo c;
    c.level = static_cast<int>(attr.depth);
    c.type = attr.type == HWLOC_OBJ_CACHE_DATA          ? "data"
             : attr.type == HWLOC_OBJ_CACHE_INSTRUCTION ? "instruction"
                                                        : "unified";
    c.size_bytes = attr.size;
    c.line_bytes = static_cast<int>(attr.linesize);
    c.associativity = attr.associativity;
    c.instances = count;
    c.pus_per_instance = std::max(1, hwloc_bitmap_weight(obj->cpuset));
    m.caches.push_back(c);
  }
  hwloc_topology_destroy(topology);
  if (m.pus <= 0 || m.cores <= 0) return sysfs_machine();
  m.packages = std::max(1, m.packages);
  m.numa_nodes = std::max(1, m.numa_nodes);
  return m;
}
#endif

std::string hostname() {
  char name[256] = {};
  if (gethostname(name, sizeof(name) - 1) != 0) return "unknown";
  return name;
}

std::string utc_now() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char text[32];
  std::strftime(text, sizeof(text), "%Y-%m-%dT%H:%M:%SZ", &tm);
  return text;
}

std::string proc_bind_name(omp_proc_bind_t bind) {
  switch (bind) {
    case omp_proc_bind_false:
      return "false";
    case omp_proc_bind_true:
      return "true";
    case omp_proc_bind_master:
      return "primary";
    case omp_proc_bind_close:
      return "close";
    case omp_proc_bind_spread:
      return "spread";
  }
  return "unknown";
}

std::string schedule_name() {
  omp_sched_t kind;
  int chunk = 0;
  omp_get_schedule(&kind, &chunk);
  // Strip the monotonic modifier bit.
  const int base = static_cast<int>(kind) & ~static_cast<int>(omp_sched_monotonic);
  const char* name = base == omp_sched_static    ? "static"
                     : base == omp_sched_dynamic ? "dynamic"
                     : base == omp_sched_guided  ? "guided"
                                                 : "auto";
  return fmt::format("{},{}", name, chunk);
}

int mpi_ranks_from_environment() {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_SIZE", "MPI_LOCALNRANKS"}) {
    if (const char* v = std::getenv(name)) {
      const int ranks = std::atoi(v);
      if (ranks > 0) return ranks;
    }
  }
  return 1;
}

}  // namespace

const MachineInfo& machine_info() {
#if CONTACTLAB_HAVE_HWLOC
  static const MachineInfo info = hwloc_machine();
#else
  static const MachineInfo info = sysfs_machine();
#endif
  return info;
}

BuildRecord build_record() {
  const BuildInfo& b = build_info();
  return {std::string(b.version),
          std::string(b.compiler),
          std::string(b.flags),
          std::string(b.build_type),
          b.native,
          std::string(b.git_commit),
          b.git_dirty};
}

Context collect_context(const std::string& command_line, int threads) {
  Context c;
  c.machine = machine_info();
  c.machine.hostname = hostname();
  c.build = build_record();
  OpenMpInfo& o = c.openmp;
  o.max_threads = omp_get_max_threads();
  o.threads = threads > 0 ? threads : o.max_threads;
  o.num_procs = omp_get_num_procs();
  o.version = _OPENMP;
  o.proc_bind = proc_bind_name(omp_get_proc_bind());
  o.places = omp_get_num_places();
  o.dynamic = omp_get_dynamic() != 0;
  o.default_schedule = schedule_name();
  o.env_num_threads = env("OMP_NUM_THREADS");
  o.env_proc_bind = env("OMP_PROC_BIND");
  o.env_places = env("OMP_PLACES");
  o.env_schedule = env("OMP_SCHEDULE");
  o.env_wait_policy = env("OMP_WAIT_POLICY");
  c.mpi_ranks = mpi_ranks_from_environment();
  c.simd_target = simd_target();
  const PapiInfo& p = papi_info();
  c.papi = {p.built_with_papi,   p.initialized, p.version,        p.error,
            p.hardware_counters, p.components,  p.presets_listed, p.cache_events};
  c.date_utc = utc_now();
  c.command_line = command_line;
  c.warnings = context_warnings(c);
  return c;
}

std::vector<std::string> context_warnings(const Context& c) {
  std::vector<std::string> warnings;
  if (c.openmp.proc_bind == "false") {
    warnings.push_back(
        "OpenMP threads are not bound to cores (OMP_PROC_BIND unset or false): they may migrate "
        "and timings vary; set OMP_PROC_BIND=close OMP_PLACES=cores");
  }
  const int cores = c.machine.cores > 0 ? c.machine.cores : c.openmp.num_procs;
  if (c.openmp.threads > cores) {
    warnings.push_back(fmt::format(
        "{} threads on {} cores: more threads than cores (oversubscribed); times and load "
        "imbalance do not describe the algorithm",
        c.openmp.threads, cores));
  }
  if (c.build.build_type != "Release") {
    warnings.push_back(fmt::format("build type '{}' is not Release: times are not representative",
                                   c.build.build_type));
  }
  return warnings;
}

}  // namespace contactlab::tuner
