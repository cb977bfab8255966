// The discharge CSV: time_s, step, discharged_kg, discharged_particles, particles_left.
#include "contactlab/dem/discharge.hpp"

#include <fmt/format.h>

#include <fstream>
#include <ostream>
#include <sstream>

#include "contactlab/kernels/atomic_file.hpp"

namespace contactlab::dem {
namespace {

constexpr const char* kHeader = "time_s,step,discharged_kg,discharged_particles,particles_left";

}  // namespace

DischargeRow discharge_row(const Snapshot& run) {
  const Particles& p = run.particles;
  const double level = run.settings.sink_below_z;
  DischargeRow row;
  row.time_s = run.time_s;
  row.step = run.step;
  row.discharged_kg = run.removed_mass;
  row.discharged = run.removed_count;
  for (std::size_t a = 0; a < p.size(); ++a) {
    if (p.z[a] < level) {
      row.discharged_kg += p.mass[a];
      ++row.discharged;
    }
  }
  row.left = p.size() - (row.discharged - run.removed_count);
  return row;
}

DischargeLog::DischargeLog(std::string path) : path_(std::move(path)) {
  prepare_output_file(path_);
}

void DischargeLog::record(const Snapshot& run) {
  rows_.push_back(discharge_row(run));
  write_file_atomically(path_, [&](std::ostream& out) {
    out << kHeader << '\n';
    for (const DischargeRow& r : rows_) {
      out << fmt::format("{:.17g},{},{:.17g},{},{}\n", r.time_s, r.step, r.discharged_kg,
                         r.discharged, r.left);
    }
  });
}

void DischargeLog::continue_series(double until_time_s) {
  rows_.clear();
  std::ifstream csv(path_);
  std::string line;
  std::getline(csv, line);  // header
  while (std::getline(csv, line)) {
    DischargeRow row;
    std::istringstream in(line);
    char comma;
    in >> row.time_s >> comma >> row.step >> comma >> row.discharged_kg >> comma >>
        row.discharged >> comma >> row.left;
    if (in && row.time_s <= until_time_s) rows_.push_back(row);
  }
}

}  // namespace contactlab::dem
