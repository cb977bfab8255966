// Helpers of the tuner and program tests: running the contactlab program, temporary folders,
// output paths whose folders cannot be made, a small scene.
#pragma once

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "contactlab/kernels/scene_generate.hpp"
#include "contactlab/tuner/papi_counters.hpp"

namespace contactlab::test {

struct CommandResult {
  int exit_code = -1;
  std::string output;  // stdout and stderr together
};

// Runs a shell command line, capturing its output.
inline CommandResult run_command(const std::string& command) {
  CommandResult result;
  FILE* pipe = ::popen((command + " 2>&1").c_str(), "r");
  if (!pipe) return result;
  char buffer[4096];
  std::size_t got = 0;
  while ((got = std::fread(buffer, 1, sizeof(buffer), pipe)) > 0) result.output.append(buffer, got);
  const int status = ::pclose(pipe);
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return result;
}

inline std::string contactlab_exe() { return CONTACTLAB_EXE; }

// A whole file's bytes ("" when it cannot be read).
inline std::string slurp(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// Why programs of this build cannot run under valgrind, or "" when they can: valgrind and
// AddressSanitizer both need to own the address space.
inline std::string valgrind_obstacle() {
#if defined(__SANITIZE_ADDRESS__)
  return "AddressSanitizer build: its binaries cannot run under valgrind";
#else
  if (run_command("valgrind --version").exit_code != 0) return "valgrind not on PATH";
  return "";
#endif
}

// A fresh folder under the system's temporary directory, removed with the object.
class TempDir {
 public:
  TempDir() {
    std::string pattern =
        (std::filesystem::temp_directory_path() / "contactlab-tuner-test-XXXXXX").string();
    if (!::mkdtemp(pattern.data())) throw std::runtime_error("mkdtemp failed");
    path_ = pattern;
  }
  ~TempDir() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  std::string file(const std::string& name) const { return (path_ / name).string(); }
  std::string path() const { return path_.string(); }

 private:
  std::filesystem::path path_;
};

// "OMPI_MCA_orte_tmpdir_base=DIR ": the environment that gives this test process's MPI runs
// (mpiexec, or a program started as a singleton MPI process) a base of their own for Open MPI's
// session directories, removed at exit. Two started together (two test processes under
// `ctest -j2`) race to make the shared /tmp/ompi.HOST.UID, and the loser stops ("A call to
// mkdir was unable to create the desired directory ... File exists"; seen once, 2026-12-05).
// The base is a short path right under the temporary directory: PMIx's sockets and segments
// live below it, and a socket path ends at 108 bytes.
inline std::string mpi_session_environment() {
  static const TempDir base;
  return "OMPI_MCA_orte_tmpdir_base=" + base.path() + " ";
}

// An empty folder of this name under GoogleTest's temporary directory (emptied if it exists).
inline std::string temp_dir(const std::string& name) {
  const std::filesystem::path dir =
      std::filesystem::path(testing::TempDir()) / ("contactlab_" + name);
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir.string();
}

// Output folders the programs must make (mkdir -p) and cannot make: a file where a folder
// should be.
inline constexpr const char* kInTheWay = "a file where a folder should be\n";

// Writes `blocker` (kInTheWay) and returns blocker/a/b/`name`: a path whose folders cannot be
// made.
inline std::string path_under_a_file(const std::string& blocker, const std::string& name) {
  std::ofstream(blocker) << kInTheWay;
  return blocker + "/a/b/" + name;
}

// How a program answers an output path under the file `blocker`: exit 2 and one line (no other
// output) naming the file in the way, which is untouched.
inline void expect_blocked(const CommandResult& r, const std::string& blocker) {
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
  EXPECT_EQ(r.output.rfind("contactlab: error: ", 0), 0u) << r.output;
  EXPECT_NE(r.output.find("'" + blocker + "' is a file, not a folder"), std::string::npos)
      << r.output;
  EXPECT_EQ(slurp(blocker), kInTheWay);
}

inline SceneSpec small_clustered(std::uint64_t n, double diameter = 0.02) {
  SceneSpec spec;
  spec.kind = SceneKind::kClustered;
  spec.n = n;
  spec.diameter = diameter;
  spec.seed = 7;
  return spec;
}

// Whether PAPI says it can count the events of some L1 or L2 miss formula here: then --papi
// must give a record with counts, else one with a reason. Asked of PAPI, not of the run.
inline bool papi_counts_a_miss_formula() {
  for (const auto* formulas : {&tuner::papi_l1_formulas(), &tuner::papi_l2_formulas()}) {
    for (const auto& f : *formulas) {
      if (tuner::papi_probe(f.events()).countable) return true;
    }
  }
  return false;
}

}  // namespace contactlab::test
