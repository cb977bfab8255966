// dem tile: copies of a settled periodic column cut to a silo keep every contact and its spring,
// only whole spheres inside the silo, the lowest when the target holds fewer, and run on; the
// command writes a checkpoint the silo's config restarts from.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <numbers>
#include <set>
#include <string>
#include <utility>

#include "contactlab/dem/config.hpp"
#include "contactlab/dem/engine.hpp"
#include "contactlab/dem/tile.hpp"
#include "contactlab/kernels/error.hpp"
#include "program_test_support.hpp"

namespace contactlab::dem {
namespace {

constexpr double kSide = 0.0088;  // the column's square: 4 lattice pitches of 2.2 mm

// A polydisperse column with periodic sides, settling on a floor (e = 0.2: it comes to rest soon).
nlohmann::json column_json() {
  return nlohmann::json::parse(R"({
    "schema_version": 1, "name": "column",
    "domain": {"lo": [0, 0, -0.01], "hi": [0.0088, 0.0088, 0.03], "periodic": [true, true, false]},
    "gravity": [0, 0, -9.81],
    "materials": [{"name": "glass", "density": 2500}],
    "contact": {"restitution": 0.2, "contact_time": 1e-4, "friction": 0.5},
    "time": {"dt": 2e-6, "end": 0.01, "output_every": 0.01},
    "walls": [{"type": "plane", "name": "floor", "point": [0, 0, 0], "normal": [0, 0, 1]}],
    "lattices": [{"lo": [0, 0, 0], "hi": [0.008801, 0.008801, 0.0088], "count": 64,
                  "radius_min": 0.0005, "radius_max": 0.001, "gap": 0.1, "jitter": 0.5,
                  "material": "glass", "seed": 3}]})");
}

// A silo of radius `radius` (12 mm: 3 x 3 copies of the column cover it) holding `count`.
DemConfig silo(double radius, int count) {
  nlohmann::json t = nlohmann::json::parse(R"({
    "schema_version": 1, "name": "silo",
    "domain": {"lo": [-0.013, -0.013, -0.01], "hi": [0.013, 0.013, 0.2]},
    "gravity": [0, 0, -9.81],
    "materials": [{"name": "sand", "density": 2600}, {"name": "glass", "density": 2500}],
    "contact": {"restitution": 0.5, "contact_time": 1e-4, "friction": 0.5},
    "time": {"dt": 2e-6, "end": 0.01, "output_every": 0.01},
    "walls": [{"type": "cylinder", "name": "silo", "point": [0, 0, 0], "axis": [0, 0, 1],
               "radius": 0.012},
              {"type": "plane", "name": "floor", "point": [0, 0, 0], "normal": [0, 0, 1]}],
    "lattices": [{"lo": [-0.012, -0.012, 0], "hi": [0.012, 0.012, 0.19], "count": 10,
                  "radius_min": 0.0005, "radius_max": 0.001, "material": "glass",
                  "inside_cylinder": {"point": [0, 0, 0], "radius": 0.012}}]})");
  t["walls"][0]["radius"] = radius;
  t["lattices"][0]["inside_cylinder"]["radius"] = radius;
  t["lattices"][0]["count"] = count;
  return parse_dem_config(t);
}

// The column after `steps` steps, as a checkpoint holds it.
CheckpointParts settled_column(const DemConfig& column, int steps) {
  Engine engine(column.settings, make_particles(column));
  for (int s = 0; s < steps; ++s) engine.step();
  return {0, engine.state(), engine.particles(), engine.pairs()};
}

double overlap(const Particles& p, std::size_t a, std::size_t b) {
  return p.radius[a] + p.radius[b] - std::hypot(p.x[a] - p.x[b], p.y[a] - p.y[b], p.z[a] - p.z[b]);
}

class DemTile : public ::testing::Test {
 protected:
  // One column for every test (settling it is most of their time).
  static void SetUpTestSuite() {
    column_ = new DemConfig(parse_dem_config(column_json()));
    state_ = new CheckpointParts(settled_column(*column_, 40000));
  }
  static void TearDownTestSuite() {
    delete state_;
    delete column_;
  }
  static inline const DemConfig* column_ = nullptr;
  static inline const CheckpointParts* state_ = nullptr;
};

TEST_F(DemTile, KeepsWholeSpheresInsideTheSiloEveryContactAndItsSpring) {
  const DemConfig target = silo(0.012, 600);
  const TiledBed bed = tile_column(*column_, *state_, target, {3, 3});
  const Particles& p = bed.parts.particles;
  const PairList& q = bed.parts.pairs;
  EXPECT_EQ(bed.report.copies, 9u);
  EXPECT_EQ(bed.report.laid, 9 * state_->particles.size());
  ASSERT_EQ(bed.report.kept, p.size());
  EXPECT_EQ(bed.report.over_count, 0u);
  ASSERT_GT(p.size(), 300u);  // the square's corners are cut away, most of it stays
  EXPECT_LT(p.size(), bed.report.laid);
  // Whole spheres inside; ids 0, 1, ... from the lowest up; the target's material index.
  for (std::size_t a = 0; a < p.size(); ++a) {
    EXPECT_LE(std::hypot(p.x[a], p.y[a]) + p.radius[a], 0.012 + 1e-15);
    EXPECT_EQ(p.material[a], 1);
  }
  std::vector<std::pair<std::uint32_t, double>> by_id;
  for (std::size_t a = 0; a < p.size(); ++a) by_id.emplace_back(p.id[a], p.z[a]);
  std::sort(by_id.begin(), by_id.end());
  for (std::size_t r = 0; r < by_id.size(); ++r) {
    ASSERT_EQ(by_id[r].first, r);
    if (r > 0) {
      EXPECT_LE(by_id[r - 1].second, by_id[r].second);
    }
  }
  // Every overlapping pair of the bed is in the list, with the spring its column pair had.
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::size_t> listed;
  for (std::size_t k = 0; k < q.size(); ++k) {
    EXPECT_EQ(q.image[k], 13);
    listed[{std::min(q.i[k], q.j[k]), std::max(q.i[k], q.j[k])}] = k;
  }
  EXPECT_EQ(listed.size(), q.size());
  int contacts = 0;
  for (std::size_t a = 0; a < p.size(); ++a) {
    for (std::size_t b = a + 1; b < p.size(); ++b) {
      if (overlap(p, a, b) <= 0) continue;
      ++contacts;
      EXPECT_TRUE(listed.contains({std::uint32_t(a), std::uint32_t(b)})) << a << " " << b;
    }
  }
  EXPECT_GT(contacts, 200);
  // And every pair within the skin where the list was built (x0): the list is complete until
  // the next rebuild, as the column's was.
  const double skin = 0.1 * 2.0 * *std::max_element(p.radius.begin(), p.radius.end());
  for (std::size_t a = 0; a < p.size(); ++a) {
    for (std::size_t b = a + 1; b < p.size(); ++b) {
      const double gap = std::hypot(p.x0[a] - p.x0[b], p.y0[a] - p.y0[b], p.z0[a] - p.z0[b]) -
                         p.radius[a] - p.radius[b];
      if (gap < 0.99 * skin) {
        EXPECT_TRUE(listed.contains({std::uint32_t(a), std::uint32_t(b)})) << a << " " << b;
      }
    }
  }
  // The springs: the bed's set of |h| values is the column's (each column pair in some copies).
  std::set<double> column_springs, bed_springs;
  const PairList& c = state_->pairs;
  for (std::size_t k = 0; k < c.size(); ++k) {
    column_springs.insert(std::hypot(c.hx[k], c.hy[k], c.hz[k]));
  }
  for (std::size_t k = 0; k < q.size(); ++k)
    bed_springs.insert(std::hypot(q.hx[k], q.hy[k], q.hz[k]));
  EXPECT_GT(bed_springs.size(), 20u);
  EXPECT_TRUE(std::includes(column_springs.begin(), column_springs.end(), bed_springs.begin(),
                            bed_springs.end()));
  // The floor's springs went to the target's floor (wall 1); the silo's wall has none.
  double floor_spring = 0.0, silo_spring = 0.0;
  for (std::size_t a = 0; a < p.size(); ++a) {
    floor_spring += std::abs(p.wall_spring[3][a]) + std::abs(p.wall_spring[4][a]);
    silo_spring += std::abs(p.wall_spring[0][a]) + std::abs(p.wall_spring[1][a]);
  }
  EXPECT_GT(floor_spring, 0.0);
  EXPECT_EQ(silo_spring, 0.0);
  EXPECT_EQ(bed.parts.state.time_s, state_->state.time_s);
  EXPECT_EQ(bed.parts.state.step, state_->state.step);
}

TEST_F(DemTile, TheBedRunsOnInTheTargetWithItsEnergyAccounted) {
  const DemConfig target = silo(0.012, 600);
  TiledBed bed = tile_column(*column_, *state_, target, {3, 3});
  const std::size_t kept = bed.parts.particles.size();
  Engine engine(target.settings, make_particles(target));
  engine.restore(bed.parts.state, std::move(bed.parts.particles), std::move(bed.parts.pairs));
  const Energies start = engine.energies();
  for (int s = 0; s < 500; ++s) engine.step();
  EXPECT_EQ(engine.particles().size(), kept);
  const Energies e = engine.energies();
  // The initial energy is the kept particles' at their lattice sites: they have lost energy
  // falling in the column, and lose more, never gain.
  EXPECT_GT(start.dissipated, 0.0);
  EXPECT_GE(e.dissipated, start.dissipated - 1e-12);
  EXPECT_LT(e.kinetic + e.potential, start.kinetic + start.potential + 1e-12);
}

TEST_F(DemTile, KeepsTheLowestWhenTheTargetHoldsFewer) {
  const TiledBed all = tile_column(*column_, *state_, silo(0.012, 600), {3, 3});
  const TiledBed few = tile_column(*column_, *state_, silo(0.012, 100), {3, 3});
  EXPECT_EQ(few.report.kept, 100u);
  EXPECT_EQ(few.report.over_count, all.report.kept - 100);
  std::vector<double> z_all(all.parts.particles.z.begin(), all.parts.particles.z.end()),
      z_few(few.parts.particles.z.begin(), few.parts.particles.z.end());
  std::sort(z_all.begin(), z_all.end());
  std::sort(z_few.begin(), z_few.end());
  EXPECT_TRUE(std::equal(z_few.begin(), z_few.end(), z_all.begin()));
  for (std::size_t k = 0; k < few.parts.pairs.size(); ++k) {
    EXPECT_LT(few.parts.pairs.i[k], 100u);
    EXPECT_LT(few.parts.pairs.j[k], 100u);
  }
}

TEST_F(DemTile, RefusesWhatItCannotLayOrCut) {
  EXPECT_THROW(tile_column(*column_, *state_, silo(0.012, 600), {2, 3}), InputError);
  nlohmann::json closed = column_json();
  closed["domain"]["periodic"] = {true, false, false};
  const DemConfig not_periodic = parse_dem_config(closed);
  EXPECT_THROW(tile_column(not_periodic, *state_, silo(0.012, 600), {3, 3}), InputError);
  DemConfig wrapping = silo(0.012, 600);
  wrapping.settings.domain.periodic = {true, true, false};
  EXPECT_THROW(tile_column(*column_, *state_, wrapping, {3, 3}), InputError);
  DemConfig no_silo = silo(0.012, 600);
  no_silo.lattices[0].in_cylinder = false;
  EXPECT_THROW(tile_column(*column_, *state_, no_silo, {3, 3}), InputError);
  EXPECT_NEAR(3 * kSide, 0.0264, 1e-12);  // 3 copies cover the 24 mm diameter, 2 do not
}

// experiments/dem/hopper-large-column.json is hopper-large's fill in a periodic square: the same
// powder, lattice law, contact and dt, and the silo's particles per unit of floor (up to the few
// per cent the cut at the wall removes), so 6 x 6 copies of it are the silo's bed.
TEST(DemTileConfigs, TheHopperLargeColumnIsTheSilosFillPerUnitOfFloor) {
  const std::string dir = std::string(CONTACTLAB_SOURCE_DIR) + "/experiments/dem/";
  const DemConfig column = read_dem_config(dir + "hopper-large-column.json");
  const DemConfig silo = read_dem_config(dir + "hopper-large.json");
  ASSERT_EQ(column.lattices.size(), 1u);
  ASSERT_EQ(silo.lattices.size(), 1u);
  const LatticeSpec& c = column.lattices[0];
  const LatticeSpec& s = silo.lattices[0];
  const double side = column.settings.domain.hi[0] - column.settings.domain.lo[0];
  EXPECT_EQ(side, column.settings.domain.hi[1] - column.settings.domain.lo[1]);
  const double per_floor_column = c.count / (side * side);
  const double per_floor_silo =
      s.count / (std::numbers::pi * s.cylinder_radius * s.cylinder_radius);
  EXPECT_GE(per_floor_column / per_floor_silo, 1.0);
  EXPECT_LE(per_floor_column / per_floor_silo, 1.03);
  EXPECT_GE(6 * side, 2 * s.cylinder_radius);
  EXPECT_EQ(c.radius_min, s.radius_min);
  EXPECT_EQ(c.radius_max, s.radius_max);
  EXPECT_EQ(c.distribution, s.distribution);
  EXPECT_EQ(c.sigma, s.sigma);
  EXPECT_EQ(c.gap, s.gap);
  EXPECT_EQ(c.jitter, s.jitter);
  EXPECT_EQ(c.lo[2], s.lo[2]);
  EXPECT_EQ(column.settings.dt_s, silo.settings.dt_s);
  EXPECT_EQ(column.settings.law.restitution, silo.settings.law.restitution);
  EXPECT_EQ(column.settings.law.contact_time_s, silo.settings.law.contact_time_s);
  EXPECT_EQ(column.settings.law.friction, silo.settings.law.friction);
  EXPECT_EQ(column.materials[0].density, silo.materials[0].density);
  // The column's floor is the silo's orifice plate ("bottom", at z = 0): its springs go there.
  ASSERT_EQ(column.settings.walls.size(), 1u);
  EXPECT_EQ(column.settings.walls[0].point[2], 0.0);
  EXPECT_EQ(column.settings.walls[0].name, "bottom");
  EXPECT_TRUE(
      std::any_of(silo.settings.walls.begin(), silo.settings.walls.end(), [](const Wall& w) {
        return w.name == "bottom" && w.kind == WallKind::kOrificePlate && w.point[2] == 0.0;
      }));
}

// `contactlab dem tile` end to end.
namespace cli {

namespace fs = std::filesystem;
using test::contactlab_exe;
using test::run_command;
using test::slurp;
using test::TempDir;

std::string drop_box() {
  return std::string(CONTACTLAB_SOURCE_DIR) + "/experiments/dem/drop-box.json";
}

// dem tile: the drop box's state laid 2 x 2 under a silo and cut to it is a checkpoint that silo
// config restarts from (and dem profile counts its particles, not the config's); a target
// that wraps (the drop box itself) is one line, and nothing is written.
TEST(DemTileCli, LaysCopiesUnderASiloThatRunsOnFromThem) {
  TempDir dir;
  const std::string column_chk = dir.file("drop.chk");
  auto r = run_command(contactlab_exe() + " dem run " + drop_box() + " --threads 1 --checkpoint " +
                       column_chk);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::string silo = slurp(drop_box());
  silo.replace(silo.find("\"domain\""), silo.find("\"gravity\"") - silo.find("\"domain\""),
               "\"domain\": {\"lo\": [-0.016, -0.016, 0], \"hi\": [0.016, 0.016, 0.05]},\n  ");
  silo.replace(silo.find("\"walls\": ["), 10,
               "\"walls\": [{\"type\": \"cylinder\", \"name\": \"silo\", \"point\": [0, 0, 0], "
               "\"axis\": [0, 0, 1], \"radius\": 0.015}, ");
  silo.replace(silo.find("\"lo\": [0, 0, 0.001], \"hi\": [0.016, 0.016, 0.03]"), 47,
               "\"lo\": [-0.015, -0.015, 0.001], \"hi\": [0.015, 0.015, 0.05], "
               "\"inside_cylinder\": {\"point\": [0, 0, 0], \"radius\": 0.015}");
  silo.replace(silo.find("\"count\": 216"), 12, "\"count\": 900");
  const std::string silo_path = dir.file("silo.json");
  std::ofstream(silo_path) << silo;
  const std::string out = dir.file("silo.chk");
  r = run_command(contactlab_exe() + " dem tile " + drop_box() + " --restart " + column_chk +
                  " --into " + silo_path + " --copies 2,2 --checkpoint " + out);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("4 copies of 'drop' at t = 0.004 s (864 particles)"), std::string::npos)
      << r.output;
  const std::string kept_marker = "laid under 'drop': ";
  const auto kept_at = r.output.find(kept_marker);
  ASSERT_NE(kept_at, std::string::npos) << r.output;
  const int kept = std::stoi(r.output.substr(kept_at + kept_marker.size()));
  EXPECT_LT(kept, 864);
  r = run_command(contactlab_exe() + " dem run " + silo_path + " --restart " + out +
                  " --steps 100 --threads 2");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  // dem profile from it counts the checkpoint's particles, not the config's 900.
  r = run_command(contactlab_exe() + " dem profile " + silo_path + " --restart " + out +
                  " --steps 5 --threads 1");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("'drop': " + std::to_string(kept) + " particles"), std::string::npos)
      << r.output;
  const std::string refused = dir.file("refused.chk");
  r = run_command(contactlab_exe() + " dem tile " + drop_box() + " --restart " + column_chk +
                  " --into " + drop_box() + " --copies 2,2 --checkpoint " + refused);
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("the target config 'drop' is periodic"), std::string::npos) << r.output;
  EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
  EXPECT_FALSE(fs::exists(refused));
}

}  // namespace cli

}  // namespace
}  // namespace contactlab::dem
