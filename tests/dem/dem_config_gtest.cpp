// Strict reading of DEM configs: every bad config is one error naming its JSON path.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <nlohmann/json.hpp>

#include "contactlab/dem/config.hpp"
#include "contactlab/kernels/error.hpp"

namespace contactlab::dem {
namespace {

using nlohmann::json;

json good() {
  return json::parse(R"({
    "schema_version": 1, "name": "t",
    "domain": {"lo": [0, 0, 0], "hi": [0.01, 0.01, 0.02], "periodic": [true, true, false]},
    "gravity": [0, 0, -9.81],
    "materials": [{"name": "glass", "density": 2500}],
    "contact": {"restitution": 0.5, "contact_time": 1e-4, "friction": 0.3},
    "time": {"dt": 2e-6, "end": 1e-3},
    "walls": [{"type": "plane", "point": [0, 0, 0], "normal": [0, 0, 1]},
              {"type": "cylinder", "point": [0, 0, 0], "axis": [0, 0, 1], "radius": 0.1},
              {"type": "cone", "apex": [0, 0, -1], "axis": [0, 0, 1], "half_angle": 30,
               "axial_max": 0.5, "remove_at": 0.1},
              {"type": "orifice_plate", "center": [0, 0, -2], "normal": [0, 0, 1],
               "orifice_radius": 0.01, "velocity": [0, 0, -1], "move_from": 0.1, "move_until": 0.2}],
    "particles": [{"position": [0.005, 0.005, 0.005], "radius": 0.001, "material": "glass"}],
    "lattices": [{"lo": [0, 0, 0.008], "hi": [0.01, 0.01, 0.02], "count": 8,
                  "radius_min": 5e-4, "radius_max": 1e-3, "material": "glass"}]
  })");
}

std::string error_of(const json& config) {
  try {
    const DemConfig c = parse_dem_config(config);
    Engine engine(c.settings, make_particles(c));
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(DemConfig, ReadsAGoodConfig) {
  const DemConfig c = parse_dem_config(good());
  EXPECT_EQ(c.settings.walls.size(), 4u);
  EXPECT_EQ(make_particles(c).size(), 9u);
  EXPECT_EQ(error_of(good()), "");
  EXPECT_EQ(c.settings.walls[2].kind, WallKind::kCone);
  EXPECT_DOUBLE_EQ(c.settings.walls[2].remove_at_s, 0.1);
}

// The near pairs' first margin: 0.1 of the skin unless the config says (0: the whole list).
TEST(DemConfig, ReadsTheNearMargin) {
  json config = good();
  EXPECT_EQ(parse_dem_config(config).settings.near_margin, 0.1);
  config["neighbor"] = {{"near_margin", 0}};
  EXPECT_EQ(parse_dem_config(config).settings.near_margin, 0.0);
}

TEST(DemConfig, ReadsTheSinkLevel) {
  json config = good();
  EXPECT_EQ(parse_dem_config(config).settings.sink_below_z,
            -std::numeric_limits<double>::infinity());
  config["sink"] = {{"below", -0.5}};
  EXPECT_EQ(parse_dem_config(config).settings.sink_below_z, -0.5);
}

// A log-normal lattice in a cylinder: radii in range and spread around the median, every sphere
// inside the cylinder, none overlapping (the lattice spacing is by the largest diameter).
TEST(DemConfig, LogNormalLatticeInsideACylinder) {
  json config = good();
  config.erase("particles");
  auto& l = config["lattices"][0];
  l["lo"] = {-0.02, -0.02, 0.0};
  l["hi"] = {0.02, 0.02, 0.02};
  l["count"] = 500;
  l["radius_distribution"] = "lognormal";
  l["sigma"] = 0.3;
  l["inside_cylinder"] = {{"point", {0.001, 0, 0}}, {"radius", 0.015}};
  l["jitter"] = 1.0;
  const DemConfig c = parse_dem_config(config);
  const Particles p = make_particles(c);
  ASSERT_EQ(p.size(), 500u);
  double log_sum = 0.0;
  int below_median = 0;
  const double median = std::sqrt(5e-4 * 1e-3);
  for (std::size_t a = 0; a < p.size(); ++a) {
    EXPECT_GE(p.radius[a], 5e-4);
    EXPECT_LE(p.radius[a], 1e-3);
    EXPECT_LE(std::hypot(p.x[a] - 0.001, p.y[a]) + p.radius[a], 0.015) << a;
    log_sum += std::log(p.radius[a]);
    below_median += p.radius[a] < median;
    for (std::size_t b = 0; b < a; ++b) {
      EXPECT_GE(std::hypot(p.x[a] - p.x[b], p.y[a] - p.y[b], p.z[a] - p.z[b]),
                p.radius[a] + p.radius[b]);
    }
  }
  EXPECT_NEAR(std::exp(log_sum / 500.0), median, 0.05 * median);
  EXPECT_GT(below_median, 200);
  EXPECT_LT(below_median, 300);
}

struct BadCase {
  const char* what;
  std::function<void(json&)> edit;
  const char* message;
};

TEST(DemConfig, BadConfigsGetOneClearError) {
  const std::vector<BadCase> cases{
      {"zero radius", [](json& j) { j["particles"][0]["radius"] = 0; }, "$.particles[0].radius"},
      {"negative radius", [](json& j) { j["lattices"][0]["radius_min"] = -1; },
       "$.lattices[0].radius_min"},
      {"e above 1", [](json& j) { j["contact"]["restitution"] = 1.2; }, "$.contact.restitution"},
      {"e zero", [](json& j) { j["contact"]["restitution"] = 0; }, "$.contact.restitution"},
      {"mu negative", [](json& j) { j["contact"]["friction"] = -0.1; }, "$.contact.friction"},
      {"missing dt", [](json& j) { j["time"].erase("dt"); }, "$.time: missing field 'dt'"},
      {"unknown key", [](json& j) { j["contact"]["frction"] = 1; }, "unknown field 'frction'"},
      {"density zero", [](json& j) { j["materials"][0]["density"] = 0; },
       "$.materials[0].density: must be > 0, got 0"},
      {"restitution above one", [](json& j) { j["contact"]["restitution"] = 1.5; },
       "$.contact.restitution: must be in (0, 1], got 1.5"},
      {"unknown material", [](json& j) { j["particles"][0]["material"] = "steel"; },
       "unknown material 'steel'"},
      {"wrong version", [](json& j) { j["schema_version"] = 2; }, "$.schema_version"},
      {"bad wall", [](json& j) { j["walls"][1]["radius"] = -1; }, "$.walls[1].radius"},
      {"unknown wall", [](json& j) { j["walls"][0]["type"] = "sphere"; }, "unknown wall type"},
      {"overlapping particles",
       [](json& j) {
         j["particles"].push_back(j["particles"][0]);
         j["particles"][1]["position"][0] = 0.0055;
       },
       "overlap"},
      {"particle in a wall", [](json& j) { j["particles"][0]["position"][2] = 0.0005; },
       "overlaps wall"},
      {"dt too large", [](json& j) { j["time"]["dt"] = 1e-4; }, "stable limit"},
      {"near margin above the skin",
       [](json& j) {
         j["neighbor"] = {{"near_margin", 1.5}};
       },
       "$.neighbor.near_margin: must be in [0, 1], got 1.5"},
      {"unknown distribution", [](json& j) { j["lattices"][0]["radius_distribution"] = "gamma"; },
       "$.lattices[0].radius_distribution"},
      {"log-normal without sigma",
       [](json& j) { j["lattices"][0]["radius_distribution"] = "lognormal"; },
       "$.lattices[0]: missing field 'sigma'"},
      {"unknown cylinder key",
       [](json& j) {
         j["lattices"][0]["inside_cylinder"] = {{"point", {0, 0, 0}}, {"radius", 1}, {"r", 1}};
       },
       "unknown field 'r'"},
      {"cylinder too narrow",
       [](json& j) {
         j["lattices"][0]["inside_cylinder"] = {{"point", {0.005, 0.005, 0}}, {"radius", 0.002}};
       },
       "usable lattice sites inside the cylinder"},
      {"sink without level", [](json& j) { j["sink"] = json::object(); },
       "$.sink: missing field 'below'"},
      {"sink level not a number",
       [](json& j) {
         j["sink"] = {{"below", "low"}};
       },
       "$.sink.below"},
  };
  for (const BadCase& c : cases) {
    json config = good();
    c.edit(config);
    const std::string message = error_of(config);
    EXPECT_NE(message.find(c.message), std::string::npos) << c.what << ": got '" << message << "'";
    EXPECT_EQ(message.find('\n'), std::string::npos) << c.what;
  }
}

}  // namespace
}  // namespace contactlab::dem
