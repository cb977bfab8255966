// Cache-miss counters of one run, from PAPI or from a simulated cache: the same fields either
// way, with `source` saying which, so that readers never mistake one for the other.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace contactlab::tuner {

struct EventCount {
  std::string name;
  std::uint64_t total = 0;
  std::vector<std::uint64_t> per_thread;  // empty for simulated counts (one shared cache)
};

// One simulated cache level (the simulator's set count must be a power of two).
struct CacheLevel {
  std::uint64_t size_bytes = 0;
  int associativity = 0;
  int line_bytes = 0;
  std::uint64_t sets() const {
    const std::uint64_t way_bytes = std::uint64_t(associativity) * std::uint64_t(line_bytes);
    return way_bytes ? size_bytes / way_bytes : 0;
  }
};

// A named two-level geometry for the cache simulator. callgrind simulates a first level and a
// last level; `l2` is that last level.
struct CacheGeometry {
  std::string name;  // host, fx10, custom
  CacheLevel l1;     // L1 data cache (also used for the instruction cache)
  CacheLevel l2;     // simulated as the last level
  std::string description;
  bool approximation = true;  // a model of the machine, not its measured behaviour
};

// How a simulated count was made.
struct SimulationRecord {
  CacheGeometry geometry;
  std::string simulator;  // e.g. "valgrind-3.19.0 callgrind --cache-sim=yes"
  int threads = 1;        // threads of the simulated run (they share one simulated cache)
  double wall_s = 0.0;    // wall time of the simulation
  // The simulated program and the instruction set it was compiled for: not the native
  // binary's (valgrind cannot execute AVX-512), so the instruction mix can differ from it.
  std::string executable;
  std::string code_isa;
  // What the simulated detection did, as the simulated program reports it: its candidate pair
  // tests (the divisor of misses per test; the native run's work can differ, e.g. tiles that
  // only the SIMD path makes) and its SIMD target ("off": the scalar loop). Null and empty
  // when the program did not report them (another program, a failed run, older files).
  std::optional<std::uint64_t> candidate_tests;
  std::string simd_target;
};

struct CounterRecord {
  std::string source;  // "papi" or "simulated:<geometry name>"
  bool available = false;
  std::string reason;  // why nothing was counted; empty when available
  // Misses per 100 data accesses (loads and stores); null when not counted.
  std::optional<double> l1_miss_percent;
  std::optional<double> l2_miss_percent;
  std::string l1_formula;  // e.g. "100 * PAPI_L1_DCM / PAPI_LST_INS"; empty without a rate
  std::string l2_formula;
  std::string region;  // what was counted, e.g. "detection loop, every thread"
  int counted_runs = 0;
  std::vector<EventCount> events;
  std::optional<SimulationRecord> simulation;  // set exactly for simulated sources
  std::vector<std::string> notes;
};

}  // namespace contactlab::tuner
