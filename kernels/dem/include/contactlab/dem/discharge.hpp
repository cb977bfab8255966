// The discharge time series of a run with a sink (a hopper): the mass that has passed the sink
// level and the particles left above it, as a CSV rewritten atomically at every output.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "contactlab/dem/engine.hpp"

namespace contactlab::dem {

struct DischargeRow {
  double time_s = 0.0;
  std::uint64_t step = 0;
  double discharged_kg = 0.0;    // removed by the sink + still present below its level
  std::uint64_t discharged = 0;  // particles, counted the same way
  std::uint64_t left = 0;        // particles above the sink level
};

// Exact at the run's time, whatever the rebuild times: the particles below the sink level
// that the next rebuild will remove are counted as discharged already.
DischargeRow discharge_row(const Snapshot& run);

class DischargeLog {
 public:
  // Makes the file's folder (and those above it) if missing; throws InputError if it cannot be
  // made or is not writable.
  explicit DischargeLog(std::string path);
  // Appends the run's row and rewrites the file.
  void record(const Snapshot& run);
  // A restarted run continues the series: the rows of the file up to this time are kept.
  void continue_series(double until_time_s);
  const std::vector<DischargeRow>& rows() const { return rows_; }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  std::vector<DischargeRow> rows_;
};

}  // namespace contactlab::dem
