// DEM output for ParaView and plots: a .vtp file per frame and the .pvd series that lists them,
// and the energy time series (CSV). Every file is written atomically.
#pragma once

#include <string>
#include <vector>

#include "contactlab/dem/engine.hpp"

namespace contactlab::dem {

class FrameWriter {
 public:
  // Frames go to dir/<name>_<frame>.vtp, the series to dir/<name>.pvd, energies to
  // dir/<name>_energy.csv. Makes dir (and the folders above it) if missing; throws InputError
  // if it cannot be made or is not writable.
  FrameWriter(std::string dir, std::string name);
  // Writes frame `frame` (particles in stable-id order: id, radius, velocity, angular velocity,
  // contact count, contact force magnitude) and rewrites the .pvd and the CSV.
  void write(const Snapshot& run, int frame);
  // Restarted runs continue a series: the entries before the restart's time are kept.
  void continue_series(double until_time_s, int frames);
  std::string frame_path(int frame) const;

 private:
  struct Entry {
    double time_s;
    std::string file;
  };
  struct EnergyRow {
    double time_s;
    std::uint64_t step;
    Energies energies;
  };
  std::string dir_, name_;
  std::vector<Entry> entries_;
  std::vector<EnergyRow> energy_;
};

}  // namespace contactlab::dem
