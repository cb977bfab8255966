// Strict reading of DEM configs: every bad config is one error naming its JSON path.
#include <gtest/gtest.h>

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
      {"density zero", [](json& j) { j["materials"][0]["density"] = 0; }, "$.materials[0].density"},
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
