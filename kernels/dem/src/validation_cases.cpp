// The validation cases: normal impacts, elastic gas, momentum, resting column, Chung & Ooi
// test 4, slide-to-roll, stability checks. Expected values are the analytic laws.
#include <fmt/format.h>

#include <cmath>
#include <numbers>

#include "contactlab/dem/validation.hpp"
#include "contactlab/kernels/error.hpp"
#include "contactlab/kernels/rng.hpp"

namespace contactlab::dem {
namespace {

constexpr double kDensity = 2500.0;  // kg/m^3 (glass)
constexpr double kRadius = 1e-3;     // m
constexpr double kTc = 1e-4;         // s

ContactLaw impact_law(double e, bool clamp) {
  ContactLaw law;
  law.restitution = e;
  law.contact_time_s = kTc;
  law.friction = 0.0;
  law.clamp_normal_force = clamp;
  return law;
}

// A case in the box [-1, 1]^3 m above the plane z = 0 (the wall "floor"), with `law`; its
// table is the output, so large overlaps do not warn.
EngineSettings on_a_floor(const ContactLaw& law) {
  EngineSettings s = validation_engine();
  s.warn_large_overlaps = false;
  s.law = law;
  s.domain.lo = {-1, -1, -1};
  s.domain.hi = {1, 1, 1};
  Wall floor;
  floor.name = "floor";
  s.walls.push_back(floor);
  return s;
}

// Sphere-sphere (1:1, 3:1) and sphere-wall at e = 0.1, 0.5, 0.9, clamped (the default) and
// not: e within 0.01 of the prediction, contact time within 1 %.
std::vector<ValidationRow> normal_impacts() {
  std::vector<ValidationRow> rows;
  struct Geometry {
    const char* name;
    double r1, r2;
  };
  for (const Geometry g : {Geometry{"sphere-sphere 1:1", kRadius, kRadius},
                           Geometry{"sphere-sphere 3:1", 3 * kRadius, kRadius},
                           Geometry{"sphere-wall", kRadius, 0.0}}) {
    for (const double e : {0.1, 0.5, 0.9}) {
      for (const bool clamp : {true, false}) {
        const ContactLaw law = impact_law(e, clamp);
        const ImpactResult r = run_normal_impact(law, g.r1, g.r2, kDensity, 0.5, kTc / 1000,
                                                 VelocityInForces::kSynchronised);
        const ImpactPrediction want = predict_impact(pair_coefficients(law), r.m_star);
        const std::string name =
            fmt::format("impact {} e={} {}", g.name, e, clamp ? "clamped" : "unclamped");
        const char* note =
            clamp ? "clamp-predicted (F_n >= 0 ends the contact early)" : "set value, t_c";
        rows.push_back(
            make_row(name, "restitution", want.restitution, r.restitution, 0.01, false, note));
        rows.push_back(make_row(name, "contact time [s]", want.contact_time_s, r.contact_time_s,
                                0.01, true, note));
      }
    }
  }
  return rows;
}

// A few dozen elastic frictionless spheres in a closed box of six planes.
std::vector<ValidationRow> elastic_gas() {
  EngineSettings s = validation_engine();
  s.warn_large_overlaps = false;  // the table is the output
  s.law = impact_law(1.0, true);
  s.dt_s = kTc / 50;
  const double side = 0.012;  // m
  s.domain.lo = {0, 0, 0};
  s.domain.hi = {side, side, side};
  for (int a = 0; a < 3; ++a) {
    for (const int hi : {0, 1}) {
      Wall w;
      w.name = fmt::format("box{}{}", a, hi);
      w.point = {0, 0, 0};
      w.point[a] = hi ? side : 0.0;
      w.normal = {0, 0, 0};
      w.normal[a] = hi ? -1.0 : 1.0;
      s.walls.push_back(w);
    }
  }
  Particles p;
  Xoshiro256 rng(12);
  std::uint32_t id = 0;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      for (int k = 0; k < 3; ++k) {
        const double r = kRadius * (0.6 + 0.4 * rng.uniform());  // polydisperse
        p.add(id, 0, (i + 0.5) * side / 3, (j + 0.5) * side / 3, (k + 0.5) * side / 3, r, kDensity);
        p.vx[id] = 2 * rng.uniform() - 1;
        p.vy[id] = 2 * rng.uniform() - 1;
        p.vz[id] = 2 * rng.uniform() - 1;
        ++id;
      }
    }
  }
  Engine engine(s, std::move(p));
  const Energies e0 = engine.energies();
  const double total0 = e0.kinetic + e0.potential;
  engine.run_steps(100'000);
  const Energies e1 = engine.energies();
  return {make_row("elastic gas, 27 spheres in a box, 1e5 steps", "total energy [J]", total0,
                   e1.kinetic + e1.potential, 1e-3, true,
                   fmt::format("{} rebuilds", engine.rebuilds()))};
}

// Dissipative, frictional spheres in a fully periodic box: total momentum stays.
std::vector<ValidationRow> periodic_momentum() {
  EngineSettings s = validation_engine();
  s.warn_large_overlaps = false;  // the table is the output
  s.law = impact_law(0.5, true);
  s.law.friction = 0.5;
  s.dt_s = kTc / 50;
  const double side = 0.01;
  s.domain.lo = {0, 0, 0};
  s.domain.hi = {side, side, side};
  s.domain.periodic = {true, true, true};
  Particles p;
  Xoshiro256 rng(5);
  for (std::uint32_t id = 0; id < 64; ++id) {
    const double x = (id % 4 + 0.5) * side / 4, y = (id / 4 % 4 + 0.5) * side / 4;
    // NOLINTNEXTLINE(bugprone-integer-division): the lattice layer, an integer on purpose
    const double z = (id / 16 + 0.5) * side / 4;
    p.add(id, 0, x, y, z, kRadius * (0.8 + 0.2 * rng.uniform()), kDensity);
    p.vx[id] = 2 * rng.uniform() - 1;
    p.vy[id] = 2 * rng.uniform() - 1;
    p.vz[id] = 2 * rng.uniform() - 1;
    p.wx[id] = 100 * (2 * rng.uniform() - 1);
  }
  auto momentum = [](const Particles& q, int axis) {
    double sum = 0, scale = 0;
    const auto& v = axis == 0 ? q.vx : axis == 1 ? q.vy : q.vz;
    for (std::size_t k = 0; k < q.size(); ++k) {
      sum += q.mass[k] * v[k];
      scale += q.mass[k] * std::abs(v[k]);
    }
    return std::pair{sum, scale};
  };
  Engine engine(s, std::move(p));
  std::vector<ValidationRow> rows;
  std::array<std::pair<double, double>, 3> before{};
  for (int a = 0; a < 3; ++a) before[a] = momentum(engine.particles(), a);
  engine.run_steps(20'000);
  for (int a = 0; a < 3; ++a) {
    const auto after = momentum(engine.particles(), a);
    // Error relative to the momentum scale sum m |v| (the total itself may be near zero).
    rows.push_back(make_row("momentum, 64 spheres, periodic, e=0.5 mu=0.5",
                            fmt::format("P_{} / sum m|v|", "xyz"[a]),
                            before[a].first / before[a].second, after.first / before[a].second,
                            1e-12, false, "round-off (absolute, of the scale)"));
  }
  return rows;
}

// A column of N spheres on a plane: the bottom overlap carries all the weight; no creep.
std::vector<ValidationRow> resting_column() {
  const int n = 10;
  EngineSettings s = validation_engine();
  s.warn_large_overlaps = false;  // the table is the output
  s.law.kind = NormalLawKind::kStiffness;
  s.law.normal_stiffness = 1000.0;  // N/m
  s.law.normal_damping = 15000.0;   // 1/s per unit reduced mass (pair e = 0.09)
  s.law.friction = 0.5;
  s.gravity = {0, 0, -9.81};
  Particles p;
  for (int k = 0; k < n; ++k) {
    p.add(static_cast<std::uint32_t>(k), 0, 0, 0, kRadius + 2 * kRadius * k, kRadius, kDensity);
  }
  const double m = p.mass[0];
  const double tc = contact_time(pair_coefficients(s.law), 0.5 * m);
  s.dt_s = tc / 50;
  s.domain.lo = {-0.01, -0.01, 0};
  s.domain.hi = {0.01, 0.01, 0.03};
  Wall floor;
  floor.name = "floor";
  s.walls.push_back(floor);
  Engine engine(s, std::move(p));
  engine.run_steps(100'000);  // settles (dropped from zero overlaps)
  auto bottom_overlap = [&] {
    const Particles& q = engine.particles();
    const std::uint32_t b = engine.index_of(0);
    return q.radius[b] - q.z[b];
  };
  const double settled = bottom_overlap();
  const double expected = n * m * 9.81 / s.law.normal_stiffness;
  engine.run_steps(100'000);
  const double later = bottom_overlap();
  const Particles& q = engine.particles();
  double drift = 0.0;
  for (std::size_t k = 0; k < q.size(); ++k) drift = std::max(drift, std::hypot(q.x[k], q.y[k]));
  return {make_row("resting column of 10 spheres", "bottom overlap [m]", expected, settled, 0.01,
                   true, "N m g / k_n"),
          make_row("resting column of 10 spheres", "overlap change over 1e5 steps / overlap", 0.0,
                   (later - settled) / expected, 1e-6, false, "no creep"),
          make_row("resting column of 10 spheres", "largest sideways drift [m]", 0.0, drift, 1e-12,
                   false, "no creep")};
}

// Chung & Ooi (2011) test 4: oblique impact of R = 2.5 mm alumina on a plane, |v| = 3.9 m/s.
// Gross sliding (tan theta > 3.5 mu (1+e)): v_t'/v_t = 1 - mu (1+e)/tan theta, w' = 2.5 mu
// (1+e) v_n / R. Sticking throughout (tan theta < 3.5 mu, where F_t/F_n = (2/7) tan theta stays
// under mu): with k_t = 2/7 k_n and gamma_t = 2/7 gamma_n the tangential oscillator of a
// sphere (mass 2/7 m) has the normal one's frequency and damping, so the contact point's
// tangential velocity comes back as -e v_t: v_t'/v_t = (2.5 - e)/3.5, w' R / v_t = 2.5 (1+e)/3.5.
// Between the two the friction is partly mobilised: only the Coulomb bound is checked.
std::vector<ValidationRow> oblique_impacts() {
  const double r = 2.5e-3, density = 4000.0, speed = 3.9, mu = 0.092, e = 0.98, tc = 1e-5;
  std::vector<ValidationRow> rows;
  const double sliding = 3.5 * mu * (1 + e), sticking = 3.5 * mu;
  for (const double angle_deg : {5.0, 10.0, 15.0, 20.0, 30.0, 40.0, 50.0, 60.0, 70.0, 80.0, 85.0}) {
    EngineSettings s = on_a_floor(impact_law(e, true));
    s.law.contact_time_s = tc;
    s.law.friction = mu;
    s.law.tangential_damping_ratio = 2.0 / 7.0;
    s.dt_s = tc / 500;
    const double theta = angle_deg * std::numbers::pi / 180;  // from the normal
    const double vt = speed * std::sin(theta), vn = speed * std::cos(theta);
    Particles p;
    p.add(0, 0, 0, 0, r * 1.001, r, density);
    p.vx[0] = vt;
    p.vz[0] = -vn;
    Engine engine(s, std::move(p));
    bool started = false;
    for (int step = 0; step < 1'000'000; ++step) {
      engine.step();
      const bool touching = engine.particles().force_magnitude[0] > 0;
      started = started || touching;
      if (started && !touching) break;
    }
    const Particles& q = engine.particles();
    const double vt_ratio = q.vx[0] / vt;
    const double spin = q.wy[0];  // rolling towards +x spins about +y
    const double e_measured = q.vz[0] / vn;
    const std::string name = fmt::format("oblique impact {:g} deg (Chung & Ooi test 4)", angle_deg);
    const double tan_theta = std::tan(theta);
    if (tan_theta > sliding) {
      rows.push_back(make_row(name, "v_t'/v_t", 1 - mu * (1 + e) / tan_theta, vt_ratio, 0.02, true,
                              "gross sliding: 1 - mu (1+e) / tan(theta)"));
      rows.push_back(make_row(name, "omega' [rad/s]", 2.5 * mu * (1 + e) * vn / r, spin, 0.02, true,
                              "gross sliding: 2.5 mu (1+e) v_n / R"));
    } else if (tan_theta < sticking) {
      rows.push_back(make_row(name, "v_t'/v_t", (2.5 - e) / 3.5, vt_ratio, 0.02, true,
                              "sticking: (2.5 - e) / 3.5"));
      rows.push_back(make_row(name, "omega' R / v_t", 2.5 * (1 + e) / 3.5, spin * r / vt, 0.02,
                              true, "sticking: 2.5 (1+e) / 3.5"));
    } else {
      const double jt_over_mujn = (1 - vt_ratio) * vt / (mu * (1 + e_measured) * vn);
      auto row = make_row(name, "J_t / (mu J_n)", 1.0, jt_over_mujn, 1e-9, false,
                          "partial slip: at most the Coulomb bound");
      row.pass = jt_over_mujn <= 1.0 + 1e-9;
      rows.push_back(row);
    }
  }
  return rows;
}

// A sphere sliding on a plane with friction ends rolling at 5/7 of its initial speed.
std::vector<ValidationRow> slide_to_roll() {
  EngineSettings s = on_a_floor(impact_law(0.5, true));
  s.law.friction = 0.3;
  s.gravity = {0, 0, -9.81};
  s.dt_s = kTc / 50;
  Particles p;
  p.add(0, 0, 0, 0, kRadius, kRadius, kDensity);
  const double rest = 9.81 / pair_coefficients(s.law).k_per_mass;  // m g / k_n
  p.z[0] = p.z0[0] = kRadius - rest;
  const double v0 = 1.0;
  p.vx[0] = v0;
  Engine engine(s, std::move(p));
  const double slip_time = 2 * v0 / (7 * 0.3 * 9.81);
  engine.run_steps(static_cast<std::uint64_t>(1.3 * slip_time / s.dt_s));
  return {make_row("sphere sliding on a plane, mu=0.3, v0=1 m/s", "final speed / v0", 5.0 / 7.0,
                   engine.particles().vx[0] / v0, 0.01, true, "rolls at 5/7 v0")};
}

// Rolling resistance (constant torque mu_r R F_n against the rotation): a sphere rolling on a
// plane decelerates at a = 5/7 mu_r g (m a = -f, I a / R = f R - mu_r R m g).
std::vector<ValidationRow> rolling_resistance() {
  EngineSettings s = on_a_floor(impact_law(0.5, true));
  s.law.friction = 0.5;
  s.law.rolling_friction = 0.1;
  s.gravity = {0, 0, -9.81};
  s.dt_s = kTc / 50;
  Particles p;
  p.add(0, 0, 0, 0, kRadius, kRadius, kDensity);
  p.z[0] = p.z0[0] = kRadius - 9.81 / pair_coefficients(s.law).k_per_mass;
  const double v0 = 0.05;
  p.vx[0] = v0;
  p.wy[0] = v0 / kRadius;  // rolling without slip
  Engine engine(s, std::move(p));
  const double t = 0.02;  // s, before it stops (at v0 / a = 0.073 s)
  engine.run_steps(static_cast<std::uint64_t>(std::llround(t / s.dt_s)));
  return {make_row("rolling resistance mu_r=0.1, sphere rolling at 0.05 m/s",
                   "speed after 0.02 s [m/s]", v0 - 5.0 / 7.0 * 0.1 * 9.81 * t,
                   engine.particles().vx[0], 0.01, true, "v0 - 5/7 mu_r g t")};
}

// Refusals and run-time stops.
std::vector<ValidationRow> stability_checks() {
  std::vector<ValidationRow> rows;
  auto check = [&](const std::string& what, const std::function<void()>& f,
                   const std::string& must_contain) {
    std::string message = "(no error)";
    try {
      f();
    } catch (const std::exception& ex) {
      message = ex.what();
    }
    ValidationRow row =
        make_row("stability: " + what, "stopped with a message", 1, 0, 0, false, message);
    row.pass = message.find(must_contain) != std::string::npos;
    row.measured = row.pass ? 1 : 0;
    row.error = row.pass ? 0 : 1;
    rows.push_back(row);
  };
  auto two = [](double speed) {
    Particles p;
    p.add(0, 0, -1.05 * kRadius, 0, 0, kRadius, kDensity);
    p.add(1, 0, 1.05 * kRadius, 0, 0, kRadius, kDensity);
    p.vx[0] = speed;
    p.vx[1] = -speed;
    return p;
  };
  EngineSettings s = validation_engine();
  s.warn_large_overlaps = false;  // the table is the output
  s.law = impact_law(0.5, true);
  s.domain.lo = {-1, -1, -1};
  s.domain.hi = {1, 1, 1};
  const double limit = stable_time_step(pair_coefficients(s.law), 1.0);  // any m*: same in (e, t_c)
  check(
      "dt above the stable limit",
      [&] {
        EngineSettings t = s;
        t.dt_s = 1.01 * limit;
        Engine engine(t, two(1.0));
      },
      "stable limit");
  check(
      "overlap above 10 % of the diameter",
      [&] {
        EngineSettings t = s;
        t.dt_s = kTc / 50;
        t.skin = 0.5 * kRadius;
        Engine engine(t, two(20.0));
        engine.run_steps(1000);
      },
      "above 10 %");
  check(
      "a move longer than skin/2 in one step",
      [&] {
        EngineSettings t = s;
        t.dt_s = kTc / 50;
        Engine engine(t, two(600.0));
        engine.run_steps(10);
      },
      "skin/2");
  check(
      "NaN velocity",
      [&] {
        EngineSettings t = s;
        t.dt_s = kTc / 50;
        Particles p = two(1.0);
        p.vy[1] = std::nan("");
        Engine engine(t, std::move(p));
        engine.run_steps(10);
      },
      "not finite");
  return rows;
}

}  // namespace

const std::vector<ValidationCase>& validation_cases() {
  static const std::vector<ValidationCase> cases{
      {"normal-impact", "head-on impacts: e and contact time", normal_impacts},
      {"elastic-gas", "energy drift of an elastic frictionless gas in a box", elastic_gas},
      {"momentum", "momentum in a periodic dissipative gas", periodic_momentum},
      {"resting-column", "bottom overlap of a resting column; no creep", resting_column},
      {"oblique-impact", "Chung & Ooi test 4", oblique_impacts},
      {"slide-to-roll", "a sliding sphere ends rolling at 5/7 v0", slide_to_roll},
      {"rolling-resistance", "deceleration of a rolling sphere by mu_r", rolling_resistance},
      {"stability", "dt limit, overlap, move and NaN checks", stability_checks},
  };
  return cases;
}

}  // namespace contactlab::dem
