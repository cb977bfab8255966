// experiments/dem/hopper-medium.json (issue #51) at a reduced particle count: its powder,
// contact law, gate and sink in a silo scaled down with the count (so that the dead zone on the
// plate stays a few per cent of the mass, as in the full config), filled to the gate's opening
// and discharged with `dem run --until-discharged 0.9`: the run must reach 90 % and stop there.
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "../common/program_test_support.hpp"

namespace contactlab {
namespace {

TEST(DemHopperMedium, AReducedCopyDischargesTo90PerCent) {
  std::ifstream in(std::string(CONTACTLAB_SOURCE_DIR) + "/experiments/dem/hopper-medium.json");
  ASSERT_TRUE(in) << "experiments/dem/hopper-medium.json";
  nlohmann::json config = nlohmann::json::parse(in);
  // 2,000 particles in a 20 mm silo (the full one: 16,000 in 45 mm) with a 14 mm orifice
  // (9 mean diameters, 7 of the largest: no jam expected), the gate removed once they settle.
  const double silo = 0.010, orifice = 0.007;
  config["name"] = "hopper-medium-smoke";
  config["domain"]["lo"] = {-silo - 0.001, -silo - 0.001, -0.03};
  config["domain"]["hi"] = {silo + 0.001, silo + 0.001, 0.12};
  for (auto& wall : config["walls"]) {
    if (wall["type"] == "cylinder") wall["radius"] = silo;
    if (wall["type"] == "orifice_plate") wall["orifice_radius"] = orifice;
    if (wall["type"] == "plane") wall["remove_at"] = 0.25;
  }
  auto& lattice = config["lattices"][0];
  lattice["count"] = 2000;
  lattice["lo"] = {-silo, -silo, 0.0};
  lattice["hi"] = {silo, silo, 0.115};
  lattice["inside_cylinder"]["radius"] = silo;
  const std::string dir = test::temp_dir("hopper_medium");
  const std::string path = dir + "/smoke.json";
  std::ofstream(path) << config.dump(1);
  const auto r = test::run_command(test::contactlab_exe() + " dem run " + path +
                                   " --threads 2 --until-discharged 0.9");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("(--until-discharged 0.9) by t = "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(": stopping"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace contactlab
