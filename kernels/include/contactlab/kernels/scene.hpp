// Particles in a box: coordinates as separate arrays (structure of arrays), optional diameters.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace contactlab {

struct Box {
  std::array<double, 3> lo{0.0, 0.0, 0.0};
  std::array<double, 3> hi{1.0, 1.0, 1.0};

  double extent(int axis) const { return hi[axis] - lo[axis]; }
  bool contains(double x, double y, double z) const {
    return x >= lo[0] && x <= hi[0] && y >= lo[1] && y <= hi[1] && z >= lo[2] && z <= hi[2];
  }
};

// Parses "xmin,ymin,zmin,xmax,ymax,zmax"; throws InputError naming the fault.
Box parse_box(const std::string& text);

struct Scene {
  Box box;
  std::vector<double> x, y, z;
  // One diameter per particle for polydisperse scenes; empty when every particle has the
  // diameter given to the detector.
  std::vector<double> diameter;

  std::size_t size() const { return x.size(); }
  bool has_diameters() const { return !diameter.empty(); }
  void reserve(std::size_t n);
  double max_diameter() const;  // 0 when there are no per-particle diameters
};

// Throws InputError for a box that is not a positive volume, a NaN or infinite value, a
// coordinate outside the box (the closed box: x == hi is inside) or a diameter <= 0.
// `source` names where the scene came from, for the message; `first_row` is the input row of
// the scene's first particle (a share of a larger file), so messages name the file's row.
void validate_scene(const Scene& scene, const std::string& source, std::size_t first_row = 0);

// FNV-1a over the bit patterns of the box, coordinates and diameters: equal exactly when
// the scenes are bit-identical. Used to record file scenes and to test reproducibility.
std::uint64_t scene_checksum(const Scene& scene);

}  // namespace contactlab
