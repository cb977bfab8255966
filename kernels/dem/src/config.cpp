// Strict reading of DEM configs with the tuner's JSON reader (paths in every error).
#include "contactlab/dem/config.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <numbers>
#include <optional>

#include "contactlab/kernels/error.hpp"
#include "contactlab/kernels/rng.hpp"
#include "contactlab/support/json_reader.hpp"

namespace contactlab::dem {
namespace {

using nlohmann::json;
constexpr double kHuge = 1e300;

// A number field: required without a fallback; checked against (low, high] or [low, high].
double number(ObjectIn& o, const std::string& key, std::optional<double> fallback, double low,
              double high, bool low_open = false) {
  const std::optional<JsonIn> in = fallback ? o.optional_field(key) : o.field(key);
  if (!in) return *fallback;
  double v = 0;
  contactlab::read(*in, v);
  if (!std::isfinite(v) || v > high || (low_open ? v <= low : v < low)) {
    // No upper bound worth printing where `high` is kHuge: "must be > 0", not "(0.0, 1e+300]".
    const std::string bound = high >= kHuge
                                  ? std::string(low_open ? "> " : ">= ") + number_text(low)
                                  : std::string("in ") + (low_open ? "(" : "[") + number_text(low) +
                                        ", " + number_text(high) + "]";
    in->fail("must be " + bound + ", got " + in->value().dump());
  }
  return v;
}

std::string text(ObjectIn& o, const std::string& key, std::optional<std::string> fallback) {
  const std::optional<JsonIn> in = fallback ? o.optional_field(key) : o.field(key);
  if (!in) return *fallback;
  std::string v;
  contactlab::read(*in, v);
  return v;
}

Vec3 vec(ObjectIn& o, const std::string& key, std::optional<Vec3> fallback) {
  const std::optional<JsonIn> in = fallback ? o.optional_field(key) : o.field(key);
  if (!in) return *fallback;
  Vec3 v{};
  contactlab::read(*in, v);
  for (double c : v) {
    if (!std::isfinite(c)) in->fail("must be finite");
  }
  return v;
}

ContactLaw parse_contact(const JsonIn& in) {
  ObjectIn o(in);
  ContactLaw law;
  const bool by_restitution = in.value().contains("restitution");
  if (by_restitution) {
    law.kind = NormalLawKind::kRestitution;
    law.restitution = number(o, "restitution", std::nullopt, 0.0, 1.0, true);
    law.contact_time_s = number(o, "contact_time", std::nullopt, 0.0, kHuge, true);
  } else {
    if (!in.value().contains("normal_stiffness")) {
      in.fail(
          "missing field 'restitution' (with 'contact_time') or 'normal_stiffness' (with "
          "'normal_damping')");
    }
    law.kind = NormalLawKind::kStiffness;
    law.normal_stiffness = number(o, "normal_stiffness", std::nullopt, 0.0, kHuge, true);
    law.normal_damping = number(o, "normal_damping", std::nullopt, 0.0, kHuge);
  }
  law.friction = number(o, "friction", std::nullopt, 0.0, kHuge);
  law.tangential_stiffness_ratio =
      number(o, "tangential_stiffness_ratio", 2.0 / 7.0, 0.0, kHuge, true);
  law.tangential_damping_ratio = number(o, "tangential_damping_ratio", 0.5, 0.0, kHuge);
  law.rolling_friction = number(o, "rolling_friction", 0.0, 0.0, kHuge);
  if (const auto clamp = o.optional_field("clamp_normal_force")) {
    contactlab::read(*clamp, law.clamp_normal_force);
  }
  o.finish();
  if (law.kind == NormalLawKind::kStiffness) {
    // Under-damped for the lightest pair is checked by the engine's stable step.
  }
  return law;
}

Wall parse_wall(const JsonIn& in) {
  ObjectIn o(in);
  Wall w;
  const std::string type = text(o, "type", std::nullopt);
  w.name = text(o, "name", type);
  if (type == "plane") {
    w.kind = WallKind::kPlane;
    w.point = vec(o, "point", std::nullopt);
    w.normal = vec(o, "normal", std::nullopt);
  } else if (type == "cylinder" || type == "cone") {
    w.kind = type == "cylinder" ? WallKind::kCylinder : WallKind::kCone;
    w.point = vec(o, type == "cone" ? "apex" : "point", std::nullopt);
    w.normal = vec(o, "axis", std::nullopt);
    if (type == "cylinder") {
      w.radius = number(o, "radius", std::nullopt, 0.0, kHuge, true);
    } else {
      w.half_angle_rad =
          number(o, "half_angle", std::nullopt, 0.0, 90.0, true) * std::numbers::pi / 180.0;
    }
    w.axial_min = number(o, "axial_min", -kHuge, -kHuge, kHuge);
    w.axial_max = number(o, "axial_max", kHuge, -kHuge, kHuge);
  } else if (type == "orifice_plate") {
    w.kind = WallKind::kOrificePlate;
    w.point = vec(o, "center", std::nullopt);
    w.normal = vec(o, "normal", std::nullopt);
    w.radius = number(o, "orifice_radius", std::nullopt, 0.0, kHuge, true);
  } else {
    o.field("type").fail("unknown wall type '" + type + "' (plane, cylinder, cone, orifice_plate)");
  }
  w.velocity = vec(o, "velocity", Vec3{0, 0, 0});
  w.move_from_s = number(o, "move_from", 0.0, 0.0, kHuge);
  w.move_until_s = number(o, "move_until", kHuge, 0.0, kHuge);
  w.remove_at_s = number(o, "remove_at", std::numeric_limits<double>::infinity(), 0.0,
                         std::numeric_limits<double>::infinity());
  o.finish();
  validate_wall(w, in.path());
  return w;
}

ParticleSpec parse_particle(const JsonIn& in) {
  ObjectIn o(in);
  ParticleSpec s;
  s.position = vec(o, "position", std::nullopt);
  s.radius = number(o, "radius", std::nullopt, 0.0, kHuge, true);
  s.material = text(o, "material", std::nullopt);
  s.velocity = vec(o, "velocity", Vec3{0, 0, 0});
  s.angular_velocity = vec(o, "angular_velocity", Vec3{0, 0, 0});
  o.finish();
  return s;
}

LatticeSpec parse_lattice(const JsonIn& in) {
  ObjectIn o(in);
  LatticeSpec s;
  s.lo = vec(o, "lo", std::nullopt);
  s.hi = vec(o, "hi", std::nullopt);
  s.count = static_cast<std::uint32_t>(number(o, "count", std::nullopt, 1.0, 1e9));
  s.radius_min = number(o, "radius_min", std::nullopt, 0.0, kHuge, true);
  s.radius_max = number(o, "radius_max", s.radius_min, s.radius_min, kHuge);
  const std::string distribution = text(o, "radius_distribution", "uniform");
  if (distribution == "uniform") {
    s.distribution = RadiusDistribution::kUniform;
  } else if (distribution == "lognormal") {
    s.distribution = RadiusDistribution::kLogNormal;
    s.sigma = number(o, "sigma", std::nullopt, 0.0, 2.0, true);
  } else {
    o.field("radius_distribution").fail("must be 'uniform' or 'lognormal'");
  }
  if (const auto cylinder = o.optional_field("inside_cylinder")) {
    ObjectIn c(*cylinder);
    s.in_cylinder = true;
    s.cylinder_point = vec(c, "point", std::nullopt);
    s.cylinder_radius = number(c, "radius", std::nullopt, 0.0, kHuge, true);
    c.finish();
  }
  s.material = text(o, "material", std::nullopt);
  s.gap = number(o, "gap", 0.05, 0.0, 10.0);
  s.jitter = number(o, "jitter", 0.5, 0.0, 1.0);
  s.seed = static_cast<std::uint64_t>(number(o, "seed", 1.0, 0.0, 9e15));
  s.velocity = vec(o, "velocity", Vec3{0, 0, 0});
  o.finish();
  return s;
}

template <class T, class F>
std::vector<T> array_of(ObjectIn& o, const std::string& key, F parse) {
  std::vector<T> out;
  const auto in = o.optional_field(key);
  if (!in) return out;
  if (!in->value().is_array()) in->wrong_type("array");
  for (std::size_t k = 0; k < in->value().size(); ++k) {
    out.push_back(parse(JsonIn(in->value()[k], in->path() + "[" + std::to_string(k) + "]")));
  }
  return out;
}

}  // namespace

DemConfig parse_dem_config(const json& document) {
  const JsonIn root(document, "$");
  ObjectIn o(root);
  const JsonIn version_in = o.field("schema_version");
  int version = 0;
  contactlab::read(version_in, version);
  if (version != kDemConfigSchemaVersion) {
    version_in.fail("version " + std::to_string(version) + " is not supported (expected " +
                    std::to_string(kDemConfigSchemaVersion) + ")");
  }
  DemConfig c;
  c.name = text(o, "name", std::nullopt);
  if (c.name.empty() || c.name.find_first_of("/\\") != std::string::npos) {
    o.field("name").fail("must be a non-empty file name without '/'");
  }
  c.description = text(o, "description", "");
  EngineSettings& s = c.settings;
  {
    ObjectIn d(o.field("domain"));
    s.domain.lo = vec(d, "lo", std::nullopt);
    s.domain.hi = vec(d, "hi", std::nullopt);
    if (const auto p = d.optional_field("periodic")) contactlab::read(*p, s.domain.periodic);
    d.finish();
    for (int a = 0; a < 3; ++a) {
      if (!(s.domain.hi[a] > s.domain.lo[a])) o.field("domain").fail("hi must be above lo");
    }
    s.domain_bounds_particles = true;
  }
  s.gravity = vec(o, "gravity", Vec3{0, 0, 0});
  s.law = parse_contact(o.field("contact"));
  {
    ObjectIn t(o.field("time"));
    s.dt_s = number(t, "dt", std::nullopt, 0.0, kHuge, true);
    c.end_time_s = number(t, "end", std::nullopt, 0.0, kHuge);
    c.output_every_s = number(t, "output_every", 0.0, 0.0, kHuge);
    const std::string mode = text(t, "velocity_in_forces", "synchronised");
    if (mode == "synchronised") {
      s.velocity_in_forces = VelocityInForces::kSynchronised;
    } else if (mode == "half_step") {
      s.velocity_in_forces = VelocityInForces::kHalfStep;
    } else {
      t.field("velocity_in_forces").fail("must be 'synchronised' or 'half_step'");
    }
    t.finish();
  }
  if (const auto sink = o.optional_field("sink")) {
    ObjectIn k(*sink);
    s.sink_below_z = number(k, "below", std::nullopt, -kHuge, kHuge);
    k.finish();
  }
  if (const auto nb = o.optional_field("neighbor")) {
    ObjectIn n(*nb);
    s.skin = number(n, "skin", 0.0, 0.0, kHuge);
    // The near pairs' first margin, a fraction of the skin (0: the force pass on the whole list).
    s.near_margin = number(n, "near_margin", s.near_margin, 0.0, 1.0);
    n.finish();
  }
  s.initial_overlap_tolerance = number(o, "initial_overlap_tolerance", 0.01, 0.0, 0.1);
  s.viscous_damping = number(o, "viscous_damping", 0.0, 0.0, kHuge);
  c.materials = array_of<Material>(o, "materials", [](const JsonIn& in) {
    ObjectIn m(in);
    Material mat{text(m, "name", std::nullopt),
                 number(m, "density", std::nullopt, 0.0, kHuge, true)};
    m.finish();
    return mat;
  });
  if (c.materials.empty()) o.field("materials").fail("at least one material is needed");
  s.walls = array_of<Wall>(o, "walls", parse_wall);
  c.particles = array_of<ParticleSpec>(o, "particles", parse_particle);
  c.lattices = array_of<LatticeSpec>(o, "lattices", parse_lattice);
  if (c.particles.empty() && c.lattices.empty()) {
    root.fail("no particles: give 'particles' or 'lattices'");
  }
  o.finish();
  auto known = [&](const std::string& name, const std::string& where) {
    for (const Material& m : c.materials) {
      if (m.name == name) return;
    }
    throw SchemaError(where + ".material: unknown material '" + name + "'");
  };
  for (std::size_t k = 0; k < c.particles.size(); ++k) {
    known(c.particles[k].material, "$.particles[" + std::to_string(k) + "]");
  }
  for (std::size_t k = 0; k < c.lattices.size(); ++k) {
    known(c.lattices[k].material, "$.lattices[" + std::to_string(k) + "]");
  }
  return c;
}

DemConfig read_dem_config(const std::string& path) {
  std::ifstream file(path);
  if (!file) throw InputError("cannot open DEM config '" + path + "'");
  json document;
  try {
    document = json::parse(file);
  } catch (const json::parse_error& e) {
    throw InputError(path + ": not valid JSON: " + e.what());
  }
  try {
    return parse_dem_config(document);
  } catch (const SchemaError& e) {
    throw InputError(path + ": " + e.what());
  }
}

Particles make_particles(const DemConfig& config) {
  Particles p;
  auto material_index = [&](const std::string& name) {
    for (std::size_t m = 0; m < config.materials.size(); ++m) {
      if (config.materials[m].name == name) return static_cast<std::uint16_t>(m);
    }
    return std::uint16_t{0};
  };
  std::uint32_t next_id = 0;
  for (const ParticleSpec& s : config.particles) {
    const std::uint16_t m = material_index(s.material);
    p.add(next_id++, m, s.position[0], s.position[1], s.position[2], s.radius,
          config.materials[m].density);
    const std::size_t k = p.size() - 1;
    p.vx[k] = s.velocity[0];
    p.vy[k] = s.velocity[1];
    p.vz[k] = s.velocity[2];
    p.wx[k] = s.angular_velocity[0];
    p.wy[k] = s.angular_velocity[1];
    p.wz[k] = s.angular_velocity[2];
  }
  for (std::size_t l = 0; l < config.lattices.size(); ++l) {
    const LatticeSpec& s = config.lattices[l];
    const std::uint16_t m = material_index(s.material);
    const double pitch = 2.0 * s.radius_max * (1.0 + s.gap);
    std::array<std::uint64_t, 3> cells{};
    for (int a = 0; a < 3; ++a) {
      const double span = s.hi[a] - s.lo[a];
      cells[a] = span >= pitch ? static_cast<std::uint64_t>(span / pitch) : 0;
    }
    auto site_centre = [&](std::uint64_t site, int a) {
      const std::uint64_t index = a == 0   ? site % cells[0]
                                  : a == 1 ? (site / cells[0]) % cells[1]
                                           : site / (cells[0] * cells[1]);
      return s.lo[a] + (static_cast<double>(index) + 0.5) * pitch;
    };
    // A site's sphere, moved by up to half a pitch per axis, stays within sqrt(2)/2 pitch of
    // the site horizontally: such sites are inside the cylinder whatever the draw.
    auto usable = [&](std::uint64_t site) {
      if (!s.in_cylinder) return true;
      const double dx = site_centre(site, 0) - s.cylinder_point[0],
                   dy = site_centre(site, 1) - s.cylinder_point[1];
      return std::hypot(dx, dy) + std::numbers::sqrt2 / 2.0 * pitch <= s.cylinder_radius;
    };
    const std::uint64_t sites = cells[0] * cells[1] * cells[2];
    std::vector<std::uint64_t> chosen;
    chosen.reserve(s.count);
    for (std::uint64_t site = 0; site < sites && chosen.size() < s.count; ++site) {
      if (usable(site)) chosen.push_back(site);
    }
    if (chosen.size() < s.count) {
      throw InputError("$.lattices[" + std::to_string(l) + "]: the region holds " +
                       std::to_string(chosen.size()) + " usable lattice sites" +
                       (s.in_cylinder ? " inside the cylinder" : "") + ", " +
                       std::to_string(s.count) + " requested");
    }
    Xoshiro256 rng(s.seed);
    auto draw_radius = [&] {
      if (s.distribution == RadiusDistribution::kUniform || s.radius_max == s.radius_min) {
        return s.radius_min + (s.radius_max - s.radius_min) * rng.uniform();
      }
      const double log_median = 0.5 * (std::log(s.radius_min) + std::log(s.radius_max));
      for (;;) {  // Box-Muller; redrawn outside the range (at least 1/3 of draws are inside)
        const double u = rng.uniform_open(), v = rng.uniform();
        const double normal = std::sqrt(-2.0 * std::log(u)) * std::cos(2.0 * std::numbers::pi * v);
        const double r = std::exp(log_median + s.sigma * normal);
        if (r >= s.radius_min && r <= s.radius_max) return r;
      }
    };
    for (std::uint64_t site : chosen) {
      const double r = draw_radius();
      const double free = 0.5 * pitch - r;  // room around the sphere in its cell
      double pos[3];
      for (int a = 0; a < 3; ++a) {
        pos[a] = site_centre(site, a) + s.jitter * free * (2.0 * rng.uniform() - 1.0);
      }
      p.add(next_id++, m, pos[0], pos[1], pos[2], r, config.materials[m].density);
      const std::size_t q = p.size() - 1;
      p.vx[q] = s.velocity[0];
      p.vy[q] = s.velocity[1];
      p.vz[q] = s.velocity[2];
    }
  }
  return p;
}

}  // namespace contactlab::dem
