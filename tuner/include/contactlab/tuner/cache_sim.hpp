// Simulated caches: the detection loop run under valgrind's cache simulator (callgrind
// --cache-sim=yes) with a named geometry, for machines without counters and to compare with
// the FX10 of Takagi et al. (docs/measurement.md).
//
// The parent process writes the scene to a temporary binary file and runs contactlab-cachesim
// (apps/contactlab-cachesim, built beside contactlab from the same kernel sources without
// AVX-512, which valgrind cannot execute) under valgrind with collection off at start; the
// child switches collection on and off around the detection loop on every OpenMP thread
// (callgrind's collection state is per thread). The parent then reads the totals.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "contactlab/kernels/detector.hpp"
#include "contactlab/tuner/counter_record.hpp"

namespace contactlab::tuner {

// SPARC64 IXfx as commonly cited: L1D 32 KiB 2-way, 128-byte lines; shared L2 12 MiB 24-way,
// 128-byte lines. An approximation (paper-notes.md): the real L2 is shared by 16 cores and
// has hardware prefetch, neither of which the simulator models.
CacheGeometry fx10_geometry();

// This machine's L1 data cache and L2, read through hwloc (or sysfs). Throws InputError when
// they cannot be read or do not form a geometry the simulator accepts.
CacheGeometry host_geometry();

// "host", "fx10", or "custom:L1SIZE,L1WAYS,L1LINE:L2SIZE,L2WAYS,L2LINE" with sizes in bytes or
// with a K/M suffix (KiB, MiB), e.g. "custom:32K,2,128:12M,24,128". Validates the result.
// Throws InputError naming the fault.
CacheGeometry parse_cache_geometry(std::string_view text);

// The simulator's rules: power-of-two line size >= 16, power-of-two set count, size larger
// than a line, associativity at most size / line, and L2 at least as large as L1.
// Throws InputError naming the level and the fault.
void validate_geometry(const CacheGeometry& geometry);

// Whether contactlab-cachesim was built with valgrind/callgrind.h, without which it cannot
// switch collection on around the detection loop alone.
bool callgrind_toggle_compiled_in();

// The program simulated detections run: $CONTACTLAB_CACHESIM, else contactlab-cachesim beside
// the running executable.
std::string cachesim_executable();

// The instruction set contactlab-cachesim was compiled for, in words.
std::string cachesim_code_isa();

struct CacheSimRequest {
  CacheGeometry geometry;
  std::string executable;              // the program to simulate
  std::vector<std::string> arguments;  // its arguments (without argv[0])
  std::string valgrind;                // empty: $CONTACTLAB_VALGRIND, else `valgrind` on PATH
  int threads = 1;                     // recorded: threads of the simulated run
};

// Runs the simulation. Never throws for a missing valgrind, a failing child or an unreadable
// output: the record then says available: false and why (a child killed by SIGILL: valgrind
// could not execute its instructions). Throws InputError only for an invalid geometry.
CounterRecord simulate_caches(const CacheSimRequest& request);

// One detection of `scene` under `variant` and `threads`, simulated: the scene goes to a
// temporary binary file that contactlab-cachesim reads under valgrind. The same contract as
// simulate_caches; the record names the simulated program and its instruction set.
CounterRecord simulate_detection_caches(const Scene& scene, double diameter, const Variant& variant,
                                        int threads, const CacheGeometry& geometry);

// Event name -> total from a callgrind output file's "events:" and "totals:" (or "summary:")
// lines. Throws InputError naming the file when they are missing or malformed.
struct CallgrindTotals {
  std::vector<std::string> events;
  std::vector<std::uint64_t> totals;
  std::uint64_t get(std::string_view event) const;  // throws InputError when absent
};
CallgrindTotals read_callgrind_totals(const std::string& path);

}  // namespace contactlab::tuner
