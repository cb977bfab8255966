// A DEM run's config (JSON, schema-versioned, read strictly with JSON-path errors) and the
// particles it describes. Keys and units: docs/dem.md.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "contactlab/dem/engine.hpp"

namespace contactlab::dem {

inline constexpr int kDemConfigSchemaVersion = 1;

struct Material {
  std::string name;
  double density = 0.0;  // kg/m^3
};

struct ParticleSpec {
  Vec3 position{0, 0, 0};  // m
  double radius = 0.0;     // m
  std::string material;
  Vec3 velocity{0, 0, 0};          // m/s
  Vec3 angular_velocity{0, 0, 0};  // rad/s
};

// How a lattice draws its radii in [radius_min, radius_max]. kUniform: uniform in r.
// kLogNormal: ln r normal around the median sqrt(radius_min radius_max) with standard deviation
// `sigma`, draws outside the range drawn again (a truncated log-normal).
enum class RadiusDistribution { kUniform, kLogNormal };

// `count` spheres on a simple cubic lattice filling [lo, hi] row by row (x fastest), spacing
// the largest diameter x (1 + gap): no overlaps by construction and O(count), whatever the
// size distribution. Each centre is moved by up to jitter x the free gap (seeded, portable).
// With `inside_cylinder`, only the sites whose sphere lies inside that vertical cylinder are
// used (a cylindrical silo filled without touching its wall).
struct LatticeSpec {
  Vec3 lo{0, 0, 0}, hi{0, 0, 0};  // m
  std::uint32_t count = 0;
  double radius_min = 0.0, radius_max = 0.0;  // m
  RadiusDistribution distribution = RadiusDistribution::kUniform;
  double sigma = 0.0;  // log-normal: standard deviation of ln r
  bool in_cylinder = false;
  Vec3 cylinder_point{0, 0, 0};  // m, a point of the cylinder's (vertical, z) axis
  double cylinder_radius = 0.0;  // m
  std::string material;
  double gap = 0.05;
  double jitter = 0.5;
  std::uint64_t seed = 1;
  Vec3 velocity{0, 0, 0};  // m/s
};

struct DemConfig {
  std::string name;
  std::string description;
  EngineSettings settings;
  std::vector<Material> materials;
  std::vector<ParticleSpec> particles;
  std::vector<LatticeSpec> lattices;
  double end_time_s = 0.0;
  double output_every_s = 0.0;  // frames and energy rows; 0 = only the first and the last
};

// Throws SchemaError (an InputError) with the JSON path of the first problem.
DemConfig parse_dem_config(const nlohmann::json& document);
DemConfig read_dem_config(const std::string& path);

// The particles in stable-id order: explicit ones first, then each lattice's.
Particles make_particles(const DemConfig& config);

}  // namespace contactlab::dem
