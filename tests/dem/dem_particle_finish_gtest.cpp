// The particles' finish (private to the engine, src/particle_finish.hpp): eight particles at a
// time gives every array bit for bit what one particle at a time gives (the engine's thread
// count moves where ranges start), with and without the final kick, drag and gravity.
#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <vector>

#include "particle_finish.hpp"

namespace contactlab::dem::detail {
namespace {

Particles random_particles(std::size_t n, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0), positive(0.5, 2.0);
  Particles p;
  for (auto* v : {&p.vx, &p.vy, &p.vz, &p.wx, &p.wy, &p.wz, &p.fx, &p.fy, &p.fz, &p.tx, &p.ty,
                  &p.tz, &p.force_magnitude}) {
    v->resize(n);
    for (double& x : *v) x = u(rng);
  }
  for (auto* v : {&p.inv_mass, &p.inv_inertia}) {
    v->resize(n);
    for (double& x : *v) x = positive(rng);
  }
  p.contacts.assign(n, 0);
  return p;
}

bool same_bits(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0;
}

void expect_ranges_agree(const FinishTerms& terms) {
  const std::size_t n = 203;  // not a multiple of eight
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<double> kin(kKinStride * n), acc(kAccStride * n);
  for (double& x : kin) x = u(rng);
  for (double& x : acc) x = u(rng);
  for (std::size_t a = 0; a < n; ++a) {
    kin[kKinStride * a + 7] = 1.0 + 0.5 * u(rng);               // mass
    acc[kAccStride * a + 6] = static_cast<double>(rng() % 12);  // touching contacts
  }
  const Particles start = random_particles(n, rng);
  Particles whole = start, one_by_one = start;
  finish_particles(kin.data(), acc.data(), whole, terms, 0, n);
  for (std::size_t a = 0; a < n; ++a)
    finish_particles(kin.data(), acc.data(), one_by_one, terms, a, a + 1);
  EXPECT_EQ(whole.contacts, one_by_one.contacts);
  EXPECT_TRUE(same_bits(whole.force_magnitude, one_by_one.force_magnitude));
  for (auto member : {&Particles::fx, &Particles::fy, &Particles::fz, &Particles::tx,
                      &Particles::ty, &Particles::tz, &Particles::vx, &Particles::vy,
                      &Particles::vz, &Particles::wx, &Particles::wy, &Particles::wz}) {
    EXPECT_TRUE(same_bits(whole.*member, one_by_one.*member));
  }
  EXPECT_NE(whole.vx, start.vx) << "the kick must have moved something";
}

TEST(DemParticleFinish, EightAtATimeMatchesOneByOne) {
  expect_ranges_agree({0.3, {0.1, -0.2, -9.81}, 1e-5, true});
  expect_ranges_agree({0.0, {0.0, 0.0, -9.81}, 2e-6, true});
}

TEST(DemParticleFinish, WithoutKickVelocitiesStay) {
  const std::size_t n = 16;
  std::mt19937_64 rng(3);
  std::vector<double> kin(kKinStride * n, 1.0), acc(kAccStride * n, 0.5);
  Particles p = random_particles(n, rng);
  const std::vector<double> vx = p.vx;
  finish_particles(kin.data(), acc.data(), p, {0.0, {0.0, 0.0, -9.81}, 1e-5, false}, 0, n);
  EXPECT_EQ(p.vx, vx);
  EXPECT_EQ(p.contacts[3], 0);  // 0.5 touching truncates to 0
  EXPECT_DOUBLE_EQ(p.fz[5], 0.5 - 9.81);
}

}  // namespace
}  // namespace contactlab::dem::detail
