// DEM configs of the program tests (dem run in one process and over MPI), written to a
// test's temporary folder.
#pragma once

#include <fstream>
#include <string>

#include "program_test_support.hpp"

namespace contactlab::test {

// A tiny flat-bottomed hopper: 150 spheres thrown down onto a gate over a 6 mm orifice, the
// gate gone at 1 ms, a sink 2 mm below the plate.
inline std::string tiny_hopper(const TempDir& dir) {
  std::string path = dir.file("tiny-hopper.json");
  std::ofstream(path) << R"({
    "schema_version": 1, "name": "tiny",
    "domain": {"lo": [-0.009, -0.009, -0.004], "hi": [0.009, 0.009, 0.02]},
    "gravity": [0, 0, -9.81],
    "materials": [{"name": "glass", "density": 2500}],
    "contact": {"restitution": 0.9, "contact_time": 1e-4, "friction": 0.5},
    "time": {"dt": 2e-6, "end": 0.004, "output_every": 0.001},
    "walls": [
      {"type": "cylinder", "point": [0, 0, 0], "axis": [0, 0, 1], "radius": 0.008, "axial_min": 0},
      {"type": "orifice_plate", "center": [0, 0, 0], "normal": [0, 0, 1], "orifice_radius": 0.003},
      {"type": "plane", "name": "gate", "point": [0, 0, 0], "normal": [0, 0, 1], "remove_at": 0.001}],
    "sink": {"below": -0.002},
    "lattices": [{"lo": [-0.008, -0.008, 0], "hi": [0.008, 0.008, 0.02], "count": 150,
                  "radius_min": 0.0005, "radius_max": 0.00075, "radius_distribution": "lognormal",
                  "sigma": 0.2, "inside_cylinder": {"point": [0, 0, 0], "radius": 0.008},
                  "material": "glass", "seed": 3, "velocity": [0, 0, -0.8]}]
  })";
  return path;
}

// The tiny hopper with its sink at z = `below` (a number in the config's text).
inline std::string tiny_hopper_with_sink(const TempDir& dir, const std::string& below) {
  std::string text = slurp(tiny_hopper(dir));
  const std::string key = "\"below\": -0.002";
  text.replace(text.find(key), key.size(), "\"below\": " + below);
  std::string config = dir.file("sink-" + below + ".json");
  std::ofstream(config) << text;
  return config;
}

}  // namespace contactlab::test
