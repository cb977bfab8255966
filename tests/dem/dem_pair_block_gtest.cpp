// The pair kernel (private to the engine, src/pair_block.hpp): eight pairs at a time (both
// kin blocks transposed, the law on lanes, outputs transposed into records), and with AVX-512
// two such groups through the law at once (lane_pair.hpp), gives every record,
// rolling torque, spring and overlap count bit for bit what one pair at a time gives, periodic
// images (alone or mixed with plain pairs in a group of eight), touching, slipping and apart
// pairs, and ragged tails included; the engine's thread-count determinism rests on it (block
// boundaries, and with them which pairs go eight at a time, move with the thread count). And
// the force pass's flat row sums (assign_rows) against the loop per row (sum_rows).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "force_pass.hpp"
#include "pair_block.hpp"

namespace contactlab::dem::detail {
namespace {

struct PairScene {
  std::vector<double> kin, acc;
  PairList q;
  PairCoefficients c;
};

// n particles with random kinematics in a box where about half the listed pairs touch; rows of
// 0 to 5 partners j < i, a fifth of them through a periodic image with a small shift; random
// springs (many pairs slip), some overlaps above 1 % and 10 %.
PairScene pair_scene(std::size_t n, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0), radius(0.3, 0.6);
  PairScene s;
  s.kin.resize(kKinStride * n);
  s.acc.resize(kAccStride * n);
  for (std::size_t a = 0; a < n; ++a) {
    double* k = &s.kin[kKinStride * a];
    for (std::size_t f = 0; f < kKinStride; ++f) k[f] = u(rng);
    k[3] = radius(rng);
    k[7] = 1.0 + radius(rng);
  }
  for (std::size_t code = 0; code < 27; ++code)
    if (code != kNoImage) s.q.shift[code] = {0.1 * u(rng), 0.1 * u(rng), 0.1 * u(rng)};
  s.q.rows.push_back(0);
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t partners = i == 0 ? 0 : rng() % 6;
    for (std::size_t p = 0; p < partners; ++p) {
      const auto j = static_cast<std::uint32_t>(rng() % i);
      s.q.i.push_back(static_cast<std::uint32_t>(i));
      s.q.j.push_back(j);
      s.q.image.push_back(rng() % 5 == 0 ? static_cast<std::uint8_t>(rng() % 27) : kNoImage);
      const double mi = s.kin[kKinStride * i + 7], mj = s.kin[kKinStride * j + 7];
      s.q.m_star.push_back(mi * mj / (mi + mj));
      s.q.hx.push_back(0.1 * u(rng));
      s.q.hy.push_back(0.1 * u(rng));
      s.q.hz.push_back(0.1 * u(rng));
    }
    s.q.rows.push_back(static_cast<std::uint32_t>(s.q.i.size()));
  }
  s.c.k_per_mass = 50.0;
  s.c.c_per_mass = 2.0;
  s.c.kt_ratio = 2.0 / 7.0;
  s.c.ct_ratio = 0.5;
  s.c.mu = 0.5;
  s.c.mu_roll = 0.1;
  for (const double m : s.q.m_star) s.q.inv_kt.push_back(inverse_kt(s.c, m));
  const std::size_t pairs = s.q.size();
  s.q.hx_next.assign(pairs, 0.0);
  s.q.hy_next.assign(pairs, 0.0);
  s.q.hz_next.assign(pairs, 0.0);
  return s;
}

// What the one-pair form gives for the pairs ks[0 .. count): records, rolling torques, springs
// (in the order given), overlap counts.
struct OneByOne {
  std::vector<double> records, roll, hx, hy, hz;
  std::uint64_t large = 0;
  std::uint32_t bad = UINT32_MAX;
};

template <bool kRolling>
OneByOne one_by_one(const PairScene& s, const std::vector<std::uint32_t>& ks) {
  OneByOne r;
  std::vector<double> storage;
  PairBlock blk(storage);
  blk.reserve(ks.size());
  for (std::size_t b = 0; b < ks.size(); ++b) {
    PairInputs<double> in = pack_one<kRolling>(s.kin.data(), s.q, ks[b]);
    const PairOutputs<double> out = pair_law<kRolling, true>(s.c, 1e-3, in);
    store_outputs<kRolling>(blk, b, out, true, ks[0], r.large, r.bad);
    r.hx.push_back(in.hx);
    r.hy.push_back(in.hy);
    r.hz.push_back(in.hz);
  }
  r.records.assign(blk.records(), blk.records() + PairBlock::kRecordFields * ks.size());
  if (kRolling) {
    for (int axis = 0; axis < 3; ++axis)
      r.roll.insert(r.roll.end(), blk.roll(axis), blk.roll(axis) + ks.size());
  }
  return r;
}

bool same_bits(const double* a, const double* b, std::size_t count) {
  return std::memcmp(a, b, count * sizeof(double)) == 0;
}

template <bool kRolling>
void expect_rows_match_one_by_one(std::size_t first, std::size_t last, SpringsTo springs) {
  PairScene s = pair_scene(300, 7);
  const std::size_t k0 = s.q.rows[first], count = s.q.rows[last] - k0;
  std::vector<std::uint32_t> ks(count);
  for (std::size_t b = 0; b < count; ++b) ks[b] = static_cast<std::uint32_t>(k0 + b);
  const OneByOne expected = one_by_one<kRolling>(s, ks);
  std::vector<double> storage;
  PairBlock blk(storage);
  std::uint64_t large = 0;
  std::uint32_t bad = UINT32_MAX;
  pair_rows<kRolling, true>(s.kin.data(), s.q, s.c, 1e-3, first, last, springs, blk, large, bad);
  const std::string where = "rows [" + std::to_string(first) + ", " + std::to_string(last) + ")";
  EXPECT_TRUE(same_bits(blk.records(), expected.records.data(), expected.records.size())) << where;
  const auto& hx = springs == SpringsTo::kNext ? s.q.hx_next : s.q.hx;
  const auto& hz = springs == SpringsTo::kNext ? s.q.hz_next : s.q.hz;
  EXPECT_TRUE(same_bits(hx.data() + k0, expected.hx.data(), count)) << where;
  EXPECT_TRUE(same_bits(hz.data() + k0, expected.hz.data(), count)) << where;
  if (kRolling) {
    for (int axis = 0; axis < 3; ++axis)
      EXPECT_TRUE(same_bits(blk.roll(axis), expected.roll.data() + axis * count, count)) << where;
  }
  EXPECT_EQ(large, expected.large) << where;
  EXPECT_EQ(bad, expected.bad) << where;
}

TEST(DemPairBlock, EightAtATimeMatchesOneByOne) {
  // Whole list, and ranges whose pair counts leave every remainder modulo sixteen (two groups
  // at once, then one, then pairs one by one).
  expect_rows_match_one_by_one<false>(0, 300, SpringsTo::kList);
  for (std::size_t last = 40; last < 72; ++last)
    expect_rows_match_one_by_one<false>(37, last, SpringsTo::kList);
  expect_rows_match_one_by_one<false>(11, 290, SpringsTo::kNext);
}

TEST(DemPairBlock, EightAtATimeMatchesOneByOneWithRolling) {
  expect_rows_match_one_by_one<true>(0, 300, SpringsTo::kList);
  expect_rows_match_one_by_one<true>(101, 163, SpringsTo::kNext);
}

TEST(DemPairBlock, GatheredPairsMatchOneByOne) {
  // The full list's j sides: pairs out of row order, springs read and not written back.
  PairScene s = pair_scene(300, 11);
  std::vector<std::uint32_t> ks;
  for (std::size_t k = 0; k < s.q.size(); k += 3) ks.push_back(static_cast<std::uint32_t>(k));
  std::reverse(ks.begin(), ks.end());
  ks.resize(ks.size() - 5);  // a ragged tail
  const AlignedVector<double> springs_before = s.q.hx;
  const OneByOne expected = one_by_one<true>(s, ks);
  std::vector<double> storage;
  PairBlock blk(storage);
  pair_gathered<true, true>(s.kin.data(), s.q, s.c, 1e-3, ks.data(), ks.size(), blk);
  EXPECT_TRUE(same_bits(blk.records(), expected.records.data(), expected.records.size()));
  for (int axis = 0; axis < 3; ++axis)
    EXPECT_TRUE(same_bits(blk.roll(axis), expected.roll.data() + axis * ks.size(), ks.size()));
  EXPECT_EQ(s.q.hx, springs_before);
}

TEST(DemPairBlock, SceneHasEveryKindOfPair) {
  // The scene above must exercise both paths of pack_eight's image test, and the law's
  // touching, slipping, apart and overlap cases.
  const PairScene s = pair_scene(300, 7);
  int mixed = 0, plain = 0;
  for (std::size_t k = 0; k + kLanes <= s.q.size(); k += kLanes) {
    int images = 0;
    for (std::size_t l = 0; l < kLanes; ++l) images += s.q.image[k + l] != kNoImage;
    ++(images == 0 ? plain : mixed);
  }
  EXPECT_GT(mixed, 5);
  EXPECT_GT(plain, 5);
  std::vector<std::uint32_t> all(s.q.size());
  for (std::size_t k = 0; k < all.size(); ++k) all[k] = static_cast<std::uint32_t>(k);
  const OneByOne r = one_by_one<false>(s, all);
  std::size_t touching = 0, slipping = 0;
  for (std::size_t k = 0; k < all.size(); ++k) {
    const double* rec = &r.records[PairBlock::kRecordFields * k];
    if (rec[PairBlock::kTouch] == 0.0) continue;
    ++touching;
    // Slipping: |F_t| = mu F_n, where |F_t| = |n x F_t| and F_n^2 = |F|^2 - |F_t|^2.
    const double ft_sq = rec[3] * rec[3] + rec[4] * rec[4] + rec[5] * rec[5];
    const double f_sq = rec[0] * rec[0] + rec[1] * rec[1] + rec[2] * rec[2];
    const double ft = std::sqrt(ft_sq), fn = std::sqrt(f_sq - ft_sq);
    slipping += std::abs(ft - s.c.mu * fn) < 1e-6 * fn;
  }
  EXPECT_GT(touching, all.size() / 5);
  EXPECT_LT(touching, all.size() * 4 / 5);
  EXPECT_GT(slipping, 10u);
  EXPECT_GT(r.large, 5u);
  EXPECT_NE(r.bad, UINT32_MAX);
}

TEST(DemForcePass, FlatRowsMatchNestedRows) {
  // assign_rows (one loop over the pairs, a row's end a select) against sum_rows (a loop per
  // row) with the same j sides: every particle's sums bit for bit, rows without pairs included.
  PairScene s = pair_scene(300, 5);
  for (const auto& [first, last] : {std::pair<std::size_t, std::size_t>{0, 300}, {37, 101}}) {
    std::vector<double> storage;
    PairBlock blk(storage);
    std::uint64_t large = 0;
    std::uint32_t bad = UINT32_MAX;
    pair_rows<true, true>(s.kin.data(), s.q, s.c, 1e-3, first, last, SpringsTo::kNext, blk, large,
                          bad);
    std::vector<double> flat(s.acc.size(), 7.0), nested(s.acc.size(), 7.0);
    auto j_side_into = [&](std::vector<double>& acc) {
      return [&](const double* p, const double* const* roll, std::size_t k, std::size_t b) {
        const std::uint32_t j = s.q.j[k];
        subtract_j_side<true>(acc.data() + kAccStride * j, p, s.kin[kKinStride * j + 3], roll, b);
      };
    };
    assign_rows<true>(s.q, first, last, blk, s.kin.data(), flat.data(), j_side_into(flat));
    for (std::size_t a = first; a < last; ++a)
      std::fill_n(nested.data() + kAccStride * a, kAccStride, 0.0);
    sum_rows<true>(
        s.q, first, last, blk, s.kin.data(), j_side_into(nested),
        [&](std::size_t i, const Lanes& sum) { store_lanes(nested.data() + kAccStride * i, sum); });
    EXPECT_TRUE(same_bits(flat.data(), nested.data(), flat.size()))
        << "rows [" << first << ", " << last << ")";
  }
  std::size_t empty_rows = 0;
  for (std::size_t i = 0; i < 300; ++i) empty_rows += s.q.rows[i] == s.q.rows[i + 1];
  EXPECT_GT(empty_rows, 10u);
}

// The partners are prefetched on four lanes always, and with AVX-512's two groups only where the
// span's kin blocks and sums outgrow half of the core's L2.
TEST(DemPairBlock, PartnersArePrefetchedWhereTheirSpanOutgrowsL2) {
  EXPECT_GT(l2_bytes(), 0u);
  EXPECT_TRUE(prefetch_partners_of(l2_bytes() / sizeof(double)));
  EXPECT_EQ(prefetch_partners_of(64), !kTwoGroups);
}

}  // namespace
}  // namespace contactlab::dem::detail
