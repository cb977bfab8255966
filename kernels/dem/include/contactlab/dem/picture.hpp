// PNG pictures of a hopper run (drawn with cairo): a vertical cross-section slab through the
// hopper axis, each sphere coloured by the horizontal layer it started in (so the funnel and
// the "ant-lion pit" of the free surface show), and the discharged mass against time.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "contactlab/dem/discharge.hpp"
#include "contactlab/dem/engine.hpp"

namespace contactlab::dem {

struct SectionView {
  double axis_x = 0.0, axis_y = 0.0;  // m: the slab is the plane y = axis_y
  double slab_half_width = 0.0;       // m: spheres with |y - axis_y| below it are drawn
  double x_lo = 0.0, x_hi = 1.0, z_lo = 0.0, z_hi = 1.0;  // m: the window
  int plot_width_px = 600;  // the window's width on the picture; its height keeps the aspect
  int layers = 8;           // initial-height bands
};

// The axis from the first vertical cylinder wall (else the domain's centre), the window the
// domain's x and z extent, the slab 2 largest diameters either side.
SectionView section_view_for(const EngineSettings& settings, const Particles& initial);

// The band of every stable id: `layers` bands of equal particle count by initial height
// (the bottom band 0); ids absent from `initial` get band 0.
std::vector<std::uint8_t> height_layers(const Particles& initial, int layers);

class SectionPainter {
 public:
  // Pictures go to dir/<name>_section_NNNNN.png. Makes dir (and the folders above it) if
  // missing; throws InputError if it cannot be made or is not writable.
  SectionPainter(std::string dir, std::string name, SectionView view,
                 std::vector<std::uint8_t> layer_of_id);
  std::string frame_path(int frame) const;
  int width() const;
  int height() const;
  // The slab at the run's time, with the walls cut by the plane, a legend and a time label.
  void write(const Snapshot& run, int frame) const;

 private:
  std::string dir_, name_;
  SectionView view_;
  std::vector<std::uint8_t> layer_of_id_;
};

// The discharged mass against time (a line plot with axes); `path` is written atomically.
void write_discharge_plot(const std::string& path, const std::vector<DischargeRow>& rows,
                          const std::string& title);

}  // namespace contactlab::dem
