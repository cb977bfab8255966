// The cache simulation of a detection run: the kernel run under valgrind's callgrind with the
// requested geometry, its totals read back as a counter record (docs/measurement.md).
#include "contactlab/tuner/cache_sim.hpp"

#include <fcntl.h>
#include <fmt/core.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "contactlab/kernels/error.hpp"
#include "contactlab/kernels/scene_io.hpp"
#include "contactlab/tuner/context.hpp"

// POSIX has the program declare environ (glibc's unistd.h does too, only under _GNU_SOURCE).
extern char** environ;  // NOLINT(readability-redundant-declaration)

namespace contactlab::tuner {
namespace {

namespace fs = std::filesystem;

// The valgrind to run: the request's, $CONTACTLAB_VALGRIND, or `valgrind` on PATH; empty if none.
std::string find_valgrind(const std::string& requested) {
  std::string candidate = requested;
  if (candidate.empty()) {
    if (const char* v = std::getenv("CONTACTLAB_VALGRIND")) candidate = v;
  }
  if (!candidate.empty()) return ::access(candidate.c_str(), X_OK) == 0 ? candidate : "";
  const char* path = std::getenv("PATH");
  std::stringstream dirs(path ? path : "/usr/bin:/bin");
  std::string dir;
  while (std::getline(dirs, dir, ':')) {
    std::string full = (dir.empty() ? "." : dir) + "/valgrind";
    if (::access(full.c_str(), X_OK) == 0) return full;
  }
  return "";
}

std::string tail_of_file(const std::string& path, std::size_t lines) {
  std::ifstream in(path);
  std::vector<std::string> all;
  std::string line;
  while (std::getline(in, line)) {
    if (!line.empty()) all.push_back(line);
  }
  std::string out;
  for (std::size_t i = all.size() > lines ? all.size() - lines : 0; i < all.size(); ++i) {
    out += (out.empty() ? "" : " | ") + all[i];
  }
  return out;
}

std::string valgrind_version(const std::string& log_path) {
  std::ifstream in(log_path);
  std::string line;
  while (std::getline(in, line)) {
    const auto at = line.find("Using Valgrind-");
    if (at != std::string::npos) {
      const auto start = at + std::strlen("Using ");
      return line.substr(start, line.find(' ', start) - start);
    }
  }
  return "valgrind";
}

// Runs argv with stdout and stderr to `log`, OMP_WAIT_POLICY=passive added to the environment
// (spinning OpenMP threads would be simulated too and make valgrind crawl). Returns the wait
// status, or -1 with `error` set.
int run_process(const std::vector<std::string>& argv, const std::string& log, std::string& error) {
  std::vector<char*> args;
  args.reserve(argv.size() + 1);
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  std::vector<std::string> env_strings;
  for (char** e = environ; *e; ++e) {
    if (std::strncmp(*e, "OMP_WAIT_POLICY=", 16) != 0) env_strings.emplace_back(*e);
  }
  env_strings.emplace_back("OMP_WAIT_POLICY=passive");
  std::vector<char*> envp;
  envp.reserve(env_strings.size() + 1);
  for (auto& e : env_strings) envp.push_back(e.data());
  envp.push_back(nullptr);

  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  pid_t pid = 0;
  const int rc = posix_spawn(&pid, args[0], &actions, nullptr, args.data(), envp.data());
  posix_spawn_file_actions_destroy(&actions);
  if (rc != 0) {
    error = fmt::format("cannot start {}: {}", argv[0], std::strerror(rc));
    return -1;
  }
  int status = 0;
  while (waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) {
      error = fmt::format("waitpid: {}", std::strerror(errno));
      return -1;
    }
  }
  return status;
}

// The simulated run's own report (apps/contactlab-cachesim prints "candidate_tests N" and
// "simd_target T" after the detection); left unset where the program printed none.
void read_child_report(const std::string& path, SimulationRecord& sim) {
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    constexpr std::string_view kTests = "candidate_tests ", kSimd = "simd_target ";
    if (line.rfind(kTests, 0) == 0) {
      const std::string value = line.substr(kTests.size());
      if (!value.empty() && value.size() <= 19 &&
          value.find_first_not_of("0123456789") == std::string::npos) {
        sim.candidate_tests = std::stoull(value);
      }
    } else if (line.rfind(kSimd, 0) == 0) {
      sim.simd_target = line.substr(kSimd.size());
    }
  }
}

std::string level_flag(const CacheLevel& c) {
  return fmt::format("{},{},{}", c.size_bytes, c.associativity, c.line_bytes);
}

constexpr const char* kRegion =
    "detection loop, every OpenMP thread (collection toggled per thread)";

}  // namespace

bool callgrind_toggle_compiled_in() {
#if CONTACTLAB_HAVE_CALLGRIND_H
  return true;
#else
  return false;
#endif
}

std::string cachesim_executable() {
  if (const char* path = std::getenv("CONTACTLAB_CACHESIM"); path && *path) return path;
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  return ((ec ? fs::path(".") : self.parent_path()) / "contactlab-cachesim").string();
}

std::string cachesim_code_isa() { return CONTACTLAB_CACHESIM_ISA; }

std::uint64_t CallgrindTotals::get(std::string_view event) const {
  for (std::size_t i = 0; i < events.size(); ++i) {
    if (events[i] == event) return i < totals.size() ? totals[i] : 0;
  }
  throw InputError(
      fmt::format("callgrind output has no event '{}' (was --cache-sim=yes given?)", event));
}

CallgrindTotals read_callgrind_totals(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot open callgrind output: " + std::strerror(errno));
  CallgrindTotals t;
  std::string line, totals_line, summary_line;
  while (std::getline(in, line)) {
    if (line.rfind("events:", 0) == 0) {
      std::istringstream words(line.substr(7));
      t.events.clear();
      for (std::string w; words >> w;) t.events.push_back(w);
    } else if (line.rfind("totals:", 0) == 0) {
      totals_line = line.substr(7);
    } else if (line.rfind("summary:", 0) == 0) {
      summary_line = line.substr(8);
    }
  }
  if (t.events.empty()) throw InputError(path + ": no 'events:' line in callgrind output");
  const std::string& values = !totals_line.empty() ? totals_line : summary_line;
  if (values.empty())
    throw InputError(path + ": no 'totals:' or 'summary:' line in callgrind output");
  std::istringstream words(values);
  for (std::string w; words >> w;) {
    if (w.find_first_not_of("0123456789") != std::string::npos) {
      throw InputError(path + ": malformed totals value '" + w + "'");
    }
    t.totals.push_back(std::stoull(w));
  }
  // Trailing zero counts may be omitted by callgrind.
  if (t.totals.size() > t.events.size()) throw InputError(path + ": more totals than events");
  t.totals.resize(t.events.size(), 0);
  return t;
}

CounterRecord simulate_caches(const CacheSimRequest& request) {
  validate_geometry(request.geometry);
  CounterRecord r;
  r.source = "simulated:" + request.geometry.name;
  r.region = kRegion;
  SimulationRecord sim;
  sim.geometry = request.geometry;
  sim.threads = request.threads;
  sim.simulator = "valgrind callgrind --cache-sim=yes";
  sim.executable = request.executable;
  r.notes.push_back("simulated, not measured: " + request.geometry.description);
  if (request.threads > 1) {
    r.notes.push_back(
        "valgrind runs threads one at a time through ONE simulated cache: with several threads "
        "the rates describe a shared cache, not per-core L1s");
  }
  auto unavailable = [&](std::string reason) {
    r.available = false;
    r.reason = std::move(reason);
    r.simulation = sim;
    return r;
  };
  const std::string valgrind = find_valgrind(request.valgrind);
  if (valgrind.empty()) {
    return unavailable(
        request.valgrind.empty() && !std::getenv("CONTACTLAB_VALGRIND")
            ? "valgrind not found on PATH (install valgrind or set CONTACTLAB_VALGRIND)"
            : "valgrind '" +
                  (request.valgrind.empty() ? std::string(std::getenv("CONTACTLAB_VALGRIND"))
                                            : request.valgrind) +
                  "' is not an executable file");
  }

  std::error_code ec;
  std::string pattern = (fs::temp_directory_path(ec) / "contactlab-cachesim-XXXXXX").string();
  if (!::mkdtemp(pattern.data())) {
    return unavailable(
        fmt::format("cannot create a temporary directory: {}", std::strerror(errno)));
  }
  const fs::path dir(pattern);
  const std::string out_file = (dir / "callgrind.out").string();
  const std::string log_file = (dir / "valgrind.log").string();
  const std::string child_log = (dir / "child.log").string();
  const CacheLevel& l1 = request.geometry.l1;
  std::vector<std::string> argv{valgrind,
                                "--tool=callgrind",
                                "--cache-sim=yes",
                                "--D1=" + level_flag(l1),
                                "--I1=" + level_flag(l1),
                                "--LL=" + level_flag(request.geometry.l2),
                                "--collect-atstart=no",
                                "--callgrind-out-file=" + out_file,
                                "--log-file=" + log_file,
                                request.executable};
  argv.insert(argv.end(), request.arguments.begin(), request.arguments.end());

  const auto start = std::chrono::steady_clock::now();
  std::string error;
  const int status = run_process(argv, child_log, error);
  sim.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  sim.simulator = valgrind_version(log_file) + " callgrind --cache-sim=yes";
  auto finish = [&](CounterRecord record) {
    fs::remove_all(dir, ec);
    return record;
  };
  if (status < 0) return finish(unavailable(error));
  if (WIFSIGNALED(status) && WTERMSIG(status) == SIGILL) {
    return finish(unavailable(fmt::format(
        "valgrind cannot execute this binary's instructions: the simulated run of {} hit an "
        "instruction {} does not implement (killed by SIGILL); build the simulated program "
        "without that instruction set. valgrind said: {}",
        request.executable, valgrind_version(log_file), tail_of_file(log_file, 3))));
  }
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    const std::string how = WIFEXITED(status)
                                ? fmt::format("exited with status {}", WEXITSTATUS(status))
                                : fmt::format("was killed by signal {}", WTERMSIG(status));
    std::string detail = tail_of_file(child_log, 2);
    if (detail.empty()) detail = tail_of_file(log_file, 3);
    return finish(unavailable(fmt::format("the simulated run {}: {}", how, detail)));
  }
  try {
    const CallgrindTotals totals = read_callgrind_totals(out_file);
    const std::uint64_t reads = totals.get("Dr"), writes = totals.get("Dw");
    const std::uint64_t l1_misses = totals.get("D1mr") + totals.get("D1mw");
    const std::uint64_t ll_misses = totals.get("DLmr") + totals.get("DLmw");
    if (reads + writes == 0) {
      return finish(unavailable(
          "no data accesses were collected in the detection region (the program did not toggle "
          "callgrind's collection)"));
    }
    for (const char* e : {"Ir", "Dr", "Dw", "D1mr", "D1mw", "DLmr", "DLmw"}) {
      r.events.push_back({e, totals.get(e), {}});
    }
    const double accesses = static_cast<double>(reads + writes);
    r.l1_miss_percent = 100.0 * static_cast<double>(l1_misses) / accesses;
    r.l2_miss_percent = 100.0 * static_cast<double>(ll_misses) / accesses;
    r.l1_formula = "100 * (D1mr + D1mw) / (Dr + Dw) (per data access)";
    r.l2_formula = "100 * (DLmr + DLmw) / (Dr + Dw) (per data access; L2 = simulated last level)";
    r.available = true;
    r.counted_runs = 1;
    read_child_report(child_log, sim);
    r.simulation = sim;
    return finish(r);
  } catch (const InputError& e) {
    return finish(unavailable(e.what()));
  }
}

CounterRecord simulate_detection_caches(const Scene& scene, double diameter, const Variant& variant,
                                        int threads, const CacheGeometry& geometry) {
  validate_geometry(geometry);
  CacheSimRequest request;
  request.geometry = geometry;
  request.executable = cachesim_executable();
  request.threads = threads;
  auto unavailable = [&](std::string reason) {
    CounterRecord r;
    r.source = "simulated:" + geometry.name;
    r.region = kRegion;
    r.reason = std::move(reason);
    r.simulation = SimulationRecord{geometry,
                                    "valgrind callgrind --cache-sim=yes",
                                    threads,
                                    0.0,
                                    request.executable,
                                    cachesim_code_isa(),
                                    std::nullopt,
                                    ""};
    return r;
  };
  if (!callgrind_toggle_compiled_in()) {
    return unavailable(
        "built without valgrind/callgrind.h: the detection region cannot be isolated");
  }
  if (::access(request.executable.c_str(), X_OK) != 0) {
    return unavailable(
        fmt::format("the simulated program {} is missing (it is built and "
                    "installed beside contactlab; or set CONTACTLAB_CACHESIM)",
                    request.executable));
  }
  std::error_code ec;
  std::string pattern = (fs::temp_directory_path(ec) / "contactlab-scene-XXXXXX").string();
  if (!::mkdtemp(pattern.data())) {
    return unavailable(
        fmt::format("cannot create a temporary directory: {}", std::strerror(errno)));
  }
  const fs::path dir(pattern);
  const std::string scene_file = (dir / "scene.bin").string();
  CounterRecord record;
  try {
    write_binary_scene(scene, scene_file);
    request.arguments = {
        "--scene-file", scene_file,         "--diameter", fmt::format("{}", diameter),
        "--variant",    to_string(variant), "--threads",  std::to_string(threads)};
    record = simulate_caches(request);
  } catch (const InputError& e) {
    record = unavailable(e.what());
  }
  fs::remove_all(dir, ec);
  if (record.simulation) record.simulation->code_isa = cachesim_code_isa();
  return record;
}

}  // namespace contactlab::tuner
