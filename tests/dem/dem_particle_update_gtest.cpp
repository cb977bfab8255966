// The per-particle passes (private to the engine, src/particle_update.hpp): eight particles at
// a time gives every array bit for bit what one particle at a time gives (the engine's thread
// count moves where ranges start): the finish with and without the final kick, drag and
// gravity; the drift with its kinematics blocks, largest displacement and first bad particle.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "particle_update.hpp"

namespace contactlab::dem::detail {
namespace {

// (assign, not resize: GCC 12 saw resize's growth path overflow here, -Walloc-size-larger-than)
Particles random_particles(std::size_t n, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0), positive(0.5, 2.0);
  Particles p;
  for (auto* v : {&p.vx, &p.vy, &p.vz, &p.wx, &p.wy, &p.wz, &p.fx, &p.fy, &p.fz, &p.tx, &p.ty,
                  &p.tz, &p.force_magnitude}) {
    v->assign(n, 0.0);
    for (double& x : *v) x = u(rng);
  }
  for (auto* v : {&p.x, &p.y, &p.z, &p.x0, &p.y0, &p.z0}) {
    v->assign(n, 0.0);
    for (double& x : *v) x = 1e-3 * u(rng);
  }
  for (auto* v : {&p.inv_mass, &p.inv_inertia, &p.radius, &p.mass}) {
    v->assign(n, 0.0);
    for (double& x : *v) x = positive(rng);
  }
  p.contacts.assign(n, 0);
  return p;
}

template <class A, class B>
bool same_bits(const A& a, const B& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0;
}

// What a finish reads: n particles' kinematics blocks and sums, and their arrays.
struct FinishInputs {
  std::vector<double> kin, acc;
  Particles start;
};
FinishInputs finish_inputs(std::size_t n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  FinishInputs in{std::vector<double>(kKinStride * n), std::vector<double>(kAccStride * n), {}};
  for (double& x : in.kin) x = u(rng);
  for (double& x : in.acc) x = u(rng);
  for (std::size_t a = 0; a < n; ++a) {
    in.kin[kKinStride * a + 7] = 1.0 + 0.5 * u(rng);               // mass
    in.acc[kAccStride * a + 6] = static_cast<double>(rng() % 12);  // touching contacts
  }
  in.start = random_particles(n, rng);
  return in;
}

void expect_ranges_agree(const FinishTerms& terms) {
  const std::size_t n = 203;  // not a multiple of eight
  auto [kin, acc, start] = finish_inputs(n, 11);
  Particles whole = start, one_by_one = start;
  finish_particles(kin.data(), acc.data(), whole, terms, 0, n, {ForceColumns::of(whole), false});
  for (std::size_t a = 0; a < n; ++a) {
    finish_particles(kin.data(), acc.data(), one_by_one, terms, a, a + 1,
                     {ForceColumns::of(one_by_one), false});
  }
  EXPECT_EQ(whole.contacts, one_by_one.contacts);
  EXPECT_TRUE(same_bits(whole.force_magnitude, one_by_one.force_magnitude));
  for (auto member : {&Particles::fx, &Particles::fy, &Particles::fz, &Particles::tx,
                      &Particles::ty, &Particles::tz, &Particles::vx, &Particles::vy,
                      &Particles::vz, &Particles::wx, &Particles::wy, &Particles::wz}) {
    EXPECT_TRUE(same_bits(whole.*member, one_by_one.*member));
  }
  EXPECT_NE(whole.vx, start.vx) << "the kick must have moved something";
}

TEST(DemParticleUpdate, FinishEightAtATimeMatchesOneByOne) {
  expect_ranges_agree({0.3, {0.1, -0.2, -9.81}, 1e-5, true});
  expect_ranges_agree({0.0, {0.0, 0.0, -9.81}, 2e-6, true});
}

TEST(DemParticleUpdate, FinishWithoutKickVelocitiesStay) {
  const std::size_t n = 16;
  std::mt19937_64 rng(3);
  std::vector<double> kin(kKinStride * n, 1.0), acc(kAccStride * n, 0.5);
  Particles p = random_particles(n, rng);
  const AlignedVector<double> vx = p.vx;
  finish_particles(kin.data(), acc.data(), p, {0.0, {0.0, 0.0, -9.81}, 1e-5, false}, 0, n,
                   {ForceColumns::of(p), false});
  EXPECT_EQ(p.vx, vx);
  EXPECT_EQ(p.contacts[3], 0);  // 0.5 touching truncates to 0
  EXPECT_DOUBLE_EQ(p.fz[5], 0.5 - 9.81);
}

// A finish to the sums (a step that drifts the next one) leaves in each particle's sums what a
// finish to the arrays stores (force, torque, contact count, |F|), gives its force and torque
// columns (a piece's buffer from any first particle) the same bits, kicks alike, and leaves
// the arrays it does not write alone.
TEST(DemParticleUpdate, FinishToTheSumsGivesWhatTheArraysGet) {
  const std::size_t n = 203, first = 5, last = 200;  // a piece not at 0, not a multiple of 8
  auto [kin, acc, start] = finish_inputs(n, 17);
  const FinishTerms terms{0.3, {0.1, -0.2, -9.81}, 1e-5, true};
  Particles to_arrays = start, to_sums = start;
  std::vector<double> sums = acc;
  finish_particles(kin.data(), acc.data(), to_arrays, terms, first, last,
                   {ForceColumns::of(to_arrays), false});
  std::vector<double> buffer(6 * (last - first));
  const ForceColumns columns = ForceColumns::in(buffer.data(), last - first, first);
  finish_particles(kin.data(), sums.data(), to_sums, terms, first, last, {columns, true});
  for (std::size_t a = 0; a < n; ++a) {
    const double* s = &sums[kAccStride * a];
    if (a < first || a >= last) {
      EXPECT_TRUE(std::memcmp(s, &acc[kAccStride * a], kAccStride * sizeof(double)) == 0) << a;
      continue;
    }
    const std::size_t c = a - first;
    const double expected[8] = {to_arrays.fx[a],
                                to_arrays.fy[a],
                                to_arrays.fz[a],
                                to_arrays.tx[a],
                                to_arrays.ty[a],
                                to_arrays.tz[a],
                                static_cast<double>(to_arrays.contacts[a]),
                                to_arrays.force_magnitude[a]};
    EXPECT_TRUE(std::memcmp(s, expected, sizeof expected) == 0) << a;
    const double column[6] = {columns.fx[c], columns.fy[c], columns.fz[c],
                              columns.tx[c], columns.ty[c], columns.tz[c]};
    EXPECT_TRUE(std::memcmp(column, expected, sizeof column) == 0) << a;
  }
  EXPECT_TRUE(same_bits(to_sums.vx, to_arrays.vx));
  EXPECT_TRUE(same_bits(to_sums.wz, to_arrays.wz));
  EXPECT_TRUE(same_bits(to_sums.fx, start.fx)) << "the arrays are store_forces' to write";
  EXPECT_TRUE(same_bits(to_sums.force_magnitude, start.force_magnitude));
  EXPECT_EQ(to_sums.contacts, start.contacts);
}

struct Drifted {
  Particles p;
  std::vector<double> kin;
  double max_disp_sq = 0.0, max_step_sq = 0.0;
  std::uint32_t bad = UINT32_MAX;
};

// Drifts `start` over [0, n) at once or one particle at a time.
Drifted drift(const Particles& start, const DriftTerms& terms, bool one_by_one) {
  Drifted d{start, std::vector<double>(kKinStride * start.x.size(), -1.0)};
  const std::size_t n = start.x.size();
  if (!one_by_one) {
    drift_particles(d.p, d.kin.data(), terms, ForceColumns::of(d.p), 0, n, d.max_disp_sq,
                    d.max_step_sq, d.bad);
  } else {
    for (std::size_t a = 0; a < n; ++a)
      drift_particles(d.p, d.kin.data(), terms, ForceColumns::of(d.p), a, a + 1, d.max_disp_sq,
                      d.max_step_sq, d.bad);
  }
  return d;
}

// The hot particles of the near pairs (DriftTerms::hot) are left out of the largest move, eight
// at a time as one by one, from a range start on a lane group or not; nothing else changes.
TEST(DemParticleUpdate, DriftLeavesHotParticlesOutOfTheLargestMove) {
  std::mt19937_64 rng(8);
  const Particles start = random_particles(203, rng);
  const std::size_t n = start.x.size();
  // Each particle's own squared move, drifted alone.
  std::vector<double> own(n);
  for (std::size_t a = 0; a < n; ++a) {
    Drifted d{start, std::vector<double>(kKinStride * n, -1.0)};
    drift_particles(d.p, d.kin.data(), {2e-6, 1e-6, 1e-6, 1.0}, ForceColumns::of(d.p), a, a + 1,
                    d.max_disp_sq, d.max_step_sq, d.bad);
    own[a] = d.max_step_sq;
  }
  // The three fastest movers hot, and two more.
  std::vector<std::size_t> order(n);
  for (std::size_t a = 0; a < n; ++a) order[a] = a;
  std::sort(order.begin(), order.end(), [&](auto a, auto b) { return own[a] > own[b]; });
  std::vector<std::uint8_t> hot(n / 8 + 2, 0);
  for (const std::size_t a : {order[0], order[1], order[2], std::size_t{9}, std::size_t{200}}) {
    hot[a / 8] |= static_cast<std::uint8_t>(1u << (a % 8));
  }
  const DriftTerms terms{2e-6, 1e-6, 1e-6, 1.0, hot.data()};
  for (const std::size_t first : {std::size_t{0}, std::size_t{3}}) {
    double expected = 0.0;
    for (std::size_t a = first; a < n; ++a) {
      if (((hot[a / 8] >> (a % 8)) & 1) == 0) expected = std::max(expected, own[a]);
    }
    ASSERT_LT(expected, own[order[2]]);
    Drifted whole{start, std::vector<double>(kKinStride * n, -1.0)};
    drift_particles(whole.p, whole.kin.data(), terms, ForceColumns::of(whole.p), first, n,
                    whole.max_disp_sq, whole.max_step_sq, whole.bad);
    EXPECT_EQ(whole.max_step_sq, expected) << first;
    const Drifted plain = drift(start, {2e-6, 1e-6, 1e-6, 1.0}, false);
    if (first == 0) {
      EXPECT_TRUE(same_bits(whole.kin, plain.kin));
      EXPECT_TRUE(same_bits(whole.p.x, plain.p.x));
      EXPECT_EQ(whole.max_disp_sq, plain.max_disp_sq);
      EXPECT_GT(plain.max_step_sq, expected);
    }
  }
}

TEST(DemParticleUpdate, DriftEightAtATimeMatchesOneByOne) {
  std::mt19937_64 rng(5);
  const Particles start = random_particles(203, rng);
  const DriftTerms terms{2e-6, 1e-6, 1e-6, 1.0};
  const Drifted whole = drift(start, terms, false), single = drift(start, terms, true);
  EXPECT_TRUE(same_bits(whole.kin, single.kin));
  for (auto member : {&Particles::x, &Particles::y, &Particles::z, &Particles::vx, &Particles::vy,
                      &Particles::vz, &Particles::wx, &Particles::wy, &Particles::wz}) {
    EXPECT_TRUE(same_bits(whole.p.*member, single.p.*member));
  }
  EXPECT_EQ(whole.max_disp_sq, single.max_disp_sq);
  EXPECT_GT(whole.max_disp_sq, 0.0);
  EXPECT_EQ(whole.max_step_sq, single.max_step_sq);
  EXPECT_GT(whole.max_step_sq, 0.0);
  EXPECT_EQ(whole.bad, UINT32_MAX);
  EXPECT_EQ(whole.kin[kKinStride * 17 + 3], start.radius[17]);
  EXPECT_EQ(whole.kin[kKinStride * 17 + 11], 0.0);
}

TEST(DemParticleUpdate, DriftReportsTheFirstBadParticle) {
  std::mt19937_64 rng(6);
  Particles start = random_particles(40, rng);
  const DriftTerms terms{2e-6, 1e-6, 1e-6, 1e-10};  // moves up to 1e-5 m
  start.vx[29] = 10.0;                              // moves 2e-5 m: past the limit
  EXPECT_EQ(drift(start, terms, false).bad, 29u);
  start.x[21] = std::numeric_limits<double>::quiet_NaN();  // not finite, earlier
  EXPECT_EQ(drift(start, terms, false).bad, 21u);
  EXPECT_EQ(drift(start, terms, true).bad, 21u);
  start.y[38] = std::numeric_limits<double>::infinity();  // in the scalar tail, later
  EXPECT_EQ(drift(start, terms, false).bad, 21u);
  start.x[21] = 0.0;
  start.vx[29] = 0.0;
  EXPECT_EQ(drift(start, terms, false).bad, 38u);
}

}  // namespace
}  // namespace contactlab::dem::detail
