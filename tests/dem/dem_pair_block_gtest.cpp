// The pair pack (private to the engine, src/pair_block.hpp): eight pairs at a time through
// in-register transposes gives every input field bit for bit what the one-pair pack gives,
// periodic images (alone or mixed with plain pairs in a group of eight) and ragged tails
// included; the engine's thread-count determinism rests on it (block boundaries, and with
// them which pairs go eight at a time, move with the thread count).
#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <vector>

#include "pair_block.hpp"

namespace contactlab::dem::detail {
namespace {

struct PackScene {
  std::vector<double> kin, acc;
  PairList q;
};

// n particles with random kinematics; rows of 0 to 5 partners j < i, a fifth of them through
// a periodic image with its own shift.
PackScene pack_scene(std::size_t n, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0), radius(0.1, 0.5);
  PackScene s;
  s.kin.resize(kKinStride * n);
  s.acc.resize(kAccStride * n);
  for (std::size_t a = 0; a < n; ++a) {
    double* k = &s.kin[kKinStride * a];
    for (std::size_t f = 0; f < kKinStride; ++f) k[f] = u(rng);
    k[3] = radius(rng);
    k[7] = 1.0 + radius(rng);
  }
  for (std::size_t code = 0; code < 27; ++code)
    if (code != kNoImage) s.q.shift[code] = {u(rng) * 10, u(rng) * 10, u(rng) * 10};
  s.q.rows.push_back(0);
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t partners = i == 0 ? 0 : rng() % 6;
    for (std::size_t p = 0; p < partners; ++p) {
      s.q.i.push_back(static_cast<std::uint32_t>(i));
      s.q.j.push_back(static_cast<std::uint32_t>(rng() % i));
      s.q.image.push_back(rng() % 5 == 0 ? static_cast<std::uint8_t>(rng() % 27) : kNoImage);
    }
    s.q.rows.push_back(static_cast<std::uint32_t>(s.q.i.size()));
  }
  return s;
}

template <bool kRolling>
void expect_eight_at_a_time_matches_one_by_one(std::size_t first, std::size_t last) {
  PackScene s = pack_scene(300, 7);
  std::vector<double> rows_storage, pair_storage;
  PairBlock by_rows(rows_storage), by_pair(pair_storage);
  const std::size_t k0 = s.q.rows[first], count = s.q.rows[last] - k0;
  by_rows.reserve(count);
  by_pair.reserve(count);
  pack_rows<kRolling>(s.kin.data(), s.q, first, last, by_rows, s.acc.data());
  const PackTargets targets(by_pair);
  for (std::size_t k = k0; k < k0 + count; ++k) {
    const PackedI pi(s.kin.data() + kKinStride * s.q.i[k]);
    pack_pair<kRolling>(s.kin.data(), s.q, pi, k, k - k0, targets);
  }
  const int fields = kRolling ? PairBlock::kRprod + 1 : PairBlock::kSz + 1;
  for (int f = 0; f < fields; ++f) {
    const auto field = static_cast<PairBlock::Input>(f);
    EXPECT_EQ(std::memcmp(by_rows.in(field), by_pair.in(field), count * sizeof(double)), 0)
        << "field " << f << ", rows [" << first << ", " << last << ")";
  }
}

TEST(DemPairBlock, EightAtATimeMatchesOneByOne) {
  // Whole list, and ranges whose pair counts leave every remainder modulo eight.
  expect_eight_at_a_time_matches_one_by_one<false>(0, 300);
  for (std::size_t last = 40; last < 56; ++last)
    expect_eight_at_a_time_matches_one_by_one<false>(37, last);
}

TEST(DemPairBlock, EightAtATimeMatchesOneByOneWithRolling) {
  expect_eight_at_a_time_matches_one_by_one<true>(0, 300);
  expect_eight_at_a_time_matches_one_by_one<true>(101, 163);
}

TEST(DemPairBlock, SceneHasMixedAndPlainGroups) {
  // The scene above must exercise both paths of pack_eight's image test.
  const PackScene s = pack_scene(300, 7);
  int mixed = 0, plain = 0;
  for (std::size_t k = 0; k + kLanes <= s.q.size(); k += kLanes) {
    int images = 0;
    for (std::size_t l = 0; l < kLanes; ++l) images += s.q.image[k + l] != kNoImage;
    ++(images == 0 ? plain : mixed);
  }
  EXPECT_GT(mixed, 5);
  EXPECT_GT(plain, 5);
}

}  // namespace
}  // namespace contactlab::dem::detail
