// `contactlab probe`: the memory bandwidth this machine's threads draw, STREAM's triad
// (a[i] = b[i] + s c[i]) at each thread count and working-set size, and the arithmetic they
// do from registers alone, written to a machine file that the emulations read
// (tuner_model/bandwidth.hpp; docs/emulation.md, "Bandwidth"). The arithmetic says whether P
// threads compute P times as fast: where two of a VM's vCPUs are one core's hyperthreads, or
// the host shares its cores, they do not, and a loop's speed-up stops short of P for that
// reason and not its bytes.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "contactlab/tuner/context.hpp"
#include "contactlab/tuner_model/bandwidth.hpp"

namespace contactlab::tuner {

struct ProbeOptions {
  std::vector<int> threads;  // ascending, distinct, >= 1 (the command's default: 1 .. cores)
  // The three arrays together, bytes: from cache-resident to beyond any last-level cache.
  std::vector<std::uint64_t> working_sets{16ull << 20, 64ull << 20, 256ull << 20, 1ull << 30};
  int repetitions =
      5;  // timed passes per point after one untimed; the best is kept (STREAM's rule)
};

struct ProbedWorkingSet {
  std::uint64_t bytes = 0;
  std::vector<std::pair<int, double>> bytes_per_s;  // (threads, best triad bandwidth)
};

struct MachineProbe {
  std::vector<ProbedWorkingSet> working_sets;  // ascending by bytes
  // (threads, best arithmetic rate, operations a second over all threads): every thread the
  // same independent multiply-add chains in registers. Empty in machine files from before it.
  std::vector<std::pair<int, double>> operations_per_s;
};

// The arithmetic rate of `threads` threads, each running the same register-resident chains (tens
// of milliseconds; the best of `repetitions` timed runs after one untimed): operations (a
// multiply or an add) a second over all threads. Throws InputError for threads or repetitions
// below 1.
double probe_arithmetic(int threads, int repetitions);

// Throws InputError, naming the problem, for no thread counts, one below 1, counts not ascending
// and distinct, no working set, one below 3 KiB or not ascending, or repetitions < 1.
void validate(const ProbeOptions& options);

// Measures every working set at every thread count (the arrays first touched by the most
// threads, with the static schedule the timed passes use). Validates first.
MachineProbe probe_bandwidth(const ProbeOptions& options);

// The machine file (docs/emulation.md, "contactlab-machine-probe").
nlohmann::json probe_document(const MachineProbe& probe, const ProbeOptions& options,
                              const Context& context);

// A machine file read back strictly (unknown or missing fields, wrong kinds, bad curves: an
// InputError naming the file and the JSON path).
MachineProbe read_machine_file(const std::string& path);

// A working set's curve with a stated ceiling (bytes/s; 0 for none).
BandwidthCurve curve_of(const ProbedWorkingSet& set, double ceiling_bytes_per_s);

// What an emulation prices bytes against: a machine file and, beyond its thread counts, the
// ceiling the user states with its source (0 and empty for none).
struct MemorySystem {
  std::string machine_file;
  MachineProbe probe;
  double ceiling_bytes_per_s = 0.0;
  std::string ceiling_source;

  // The probed working set that holds `footprint_bytes` (else the largest: working_set_for).
  const ProbedWorkingSet& working_set(std::uint64_t footprint_bytes) const;
  // Its curve with the ceiling.
  BandwidthCurve curve(std::uint64_t footprint_bytes) const {
    return curve_of(working_set(footprint_bytes), ceiling_bytes_per_s);
  }
  // {machine_file, ceiling_bytes_per_s, ceiling_source}: what a run was told
  nlohmann::json json() const;
  // The same with {working_set_bytes, footprint_bytes}: what a footprint was priced by
  nlohmann::json json(std::uint64_t footprint_bytes) const;
  // "FILE (64 MiB working set for a 57 MiB footprint); beyond the probed threads towards C GB/s
  // (SOURCE)" or "... the last probed bandwidth (no ceiling stated)".
  std::string describe(std::uint64_t footprint_bytes) const;
};

}  // namespace contactlab::tuner
