// dem run's outputs (dem_outputs.hpp).
#include "dem_outputs.hpp"

#include <fmt/format.h>

#include <limits>

#include "contactlab/kernels/atomic_file.hpp"
#include "contactlab/kernels/error.hpp"
#ifdef CONTACTLAB_HAVE_CAIRO
#include "contactlab/dem/picture.hpp"
#else
// Without cairo there are no pictures (--png is refused): an empty painter, never made, for
// the member's destructor.
namespace contactlab::dem {
class SectionPainter {};
}  // namespace contactlab::dem
#endif

namespace contactlab::cli {
namespace {

std::string in_dir(std::string dir, const std::string& file) {
  if (!dir.empty() && dir.back() != '/') dir += '/';
  return dir + file;
}

}  // namespace

RunOutputs::RunOutputs(const DemOutputOptions& options, const dem::DemConfig& config,
                       const dem::Particles& initial)
    : name_(config.name),
      png_dir_(options.png_dir),
      sink_below_z_(config.settings.sink_below_z),
      checkpoint_(options.checkpoint) {
  if (!options.vtk_dir.empty()) {
    writer_ = std::make_unique<dem::FrameWriter>(options.vtk_dir, config.name);
  }
  if (!options.png_dir.empty()) {
#ifdef CONTACTLAB_HAVE_CAIRO
    painter_ = std::make_unique<dem::SectionPainter>(
        options.png_dir, config.name, dem::section_view_for(config.settings, initial),
        dem::height_layers(initial, dem::SectionView{}.layers));
#else
    (void)initial;
    throw InputError(
        "--png: this contactlab was built without cairo (install libcairo2-dev and rebuild)");
#endif
  }
  const bool has_sink = sink_below_z_ > -std::numeric_limits<double>::infinity();
  std::string discharge = options.discharge;
  if (discharge.empty() && has_sink && (writer_ || !png_dir_.empty())) {
    discharge = in_dir(writer_ ? options.vtk_dir : png_dir_, config.name + "_discharge.csv");
  }
  if (!discharge.empty()) log_ = std::make_unique<dem::DischargeLog>(discharge);
  if (checkpoint_.empty() && writer_) checkpoint_ = in_dir(options.vtk_dir, "last.chk");
  if (!checkpoint_.empty()) prepare_output_file(checkpoint_);
}

RunOutputs::~RunOutputs() = default;

void RunOutputs::continue_series(double time_s, int frames) {
  frames_ = frames;
  if (writer_) writer_->continue_series(time_s, frames);
  if (log_) log_->continue_series(time_s);
}

void RunOutputs::write(const dem::Snapshot& run) {
  if (writer_) writer_->write(run, frames_);
#ifdef CONTACTLAB_HAVE_CAIRO
  if (painter_) painter_->write(run, frames_);
#endif
  if (writer_ || painter_) ++frames_;
  if (log_) log_->record(run);
}

void RunOutputs::finish() const {
#ifdef CONTACTLAB_HAVE_CAIRO
  if (painter_ && log_) {
    dem::write_discharge_plot(
        in_dir(png_dir_, name_ + "_discharge.png"), log_->rows(),
        fmt::format("{}: discharged mass (sink below z = {:.4g} m)", name_, sink_below_z_));
  }
#endif
}

}  // namespace contactlab::cli
