// What `dem run` writes as it goes (--vtk frames and energies, --png sections, the discharge
// CSV, the checkpoint): made before any work, written at every output step. The same outputs
// for one process and for a decomposed run, whose rank 0 holds them and writes the snapshot
// gathered from every rank.
#pragma once

#include <memory>
#include <string>

#include "contactlab/dem/config.hpp"
#include "contactlab/dem/discharge.hpp"
#include "contactlab/dem/engine.hpp"
#include "contactlab/dem/output.hpp"

namespace contactlab::dem {
class SectionPainter;
}

namespace contactlab::cli {

struct DemOutputOptions {
  std::string vtk_dir;     // frames, the .pvd, the energy CSV, and by default last.chk
  std::string png_dir;     // section pictures and the discharge plot
  std::string discharge;   // default with a sink: <name>_discharge.csv in the vtk or png folder
  std::string checkpoint;  // default with --vtk: last.chk there
};

class RunOutputs {
 public:
  // Makes the folders and checks every path before any work (InputError naming the one that
  // cannot be written; --png without cairo is one too). `initial` sets the pictures' view and
  // their colour bands (the heights the particles start at).
  RunOutputs(const DemOutputOptions& options, const dem::DemConfig& config,
             const dem::Particles& initial);
  ~RunOutputs();
  RunOutputs(const RunOutputs&) = delete;
  RunOutputs& operator=(const RunOutputs&) = delete;

  // A restarted run continues the series of the run that wrote its checkpoint.
  void continue_series(double time_s, int frames);
  // The frame, the picture and the discharge row of the run at this step.
  void write(const dem::Snapshot& run);
  // At the end of the run: the discharge plot (with --png and a sink).
  void finish() const;
  // The frames written so far (a checkpoint records it, a restart continues from it).
  int frames() const { return frames_; }
  const std::string& checkpoint() const { return checkpoint_; }  // empty: none

 private:
  std::string name_, png_dir_;
  double sink_below_z_;
  std::string checkpoint_;
  std::unique_ptr<dem::FrameWriter> writer_;
  std::unique_ptr<dem::SectionPainter> painter_;
  std::unique_ptr<dem::DischargeLog> log_;
  int frames_ = 0;
};

}  // namespace contactlab::cli
