// The bandwidth law (tuner_model/bandwidth.hpp) on hand-computed cases: the measured points and
// the interpolation between them, the saturating curve beyond them towards a stated ceiling,
// the roofline of a phase, the working set a footprint is priced against, and bad curves.
#include <gtest/gtest.h>

#include <stdexcept>

#include "contactlab/tuner_model/bandwidth.hpp"

namespace contactlab::tuner {
namespace {

constexpr double kG = 1e9;

TEST(BandwidthCurve, MeasuredPointsHoldAndLinearBetween) {
  const BandwidthCurve curve({{1, 10 * kG}, {4, 25 * kG}}, 0.0);
  EXPECT_DOUBLE_EQ(curve.at(1), 10 * kG);
  EXPECT_DOUBLE_EQ(curve.at(2), 15 * kG);
  EXPECT_DOUBLE_EQ(curve.at(3), 20 * kG);
  EXPECT_DOUBLE_EQ(curve.at(4), 25 * kG);
  EXPECT_DOUBLE_EQ(curve.at(16), 25 * kG) << "no ceiling: the last point holds";
}

TEST(BandwidthCurve, BelowTheFirstPointScalesWithThreads) {
  const BandwidthCurve curve({{2, 18 * kG}}, 0.0);
  EXPECT_DOUBLE_EQ(curve.at(1), 9 * kG);
}

TEST(BandwidthCurve, BeyondTheLastPointSaturatesTowardsTheCeiling) {
  // Through (2, 18 GB/s) towards 50 GB/s: K = 2 (50/18 - 1) = 32/9, B(P) = 50 P / (P + 32/9).
  const BandwidthCurve curve({{1, 10 * kG}, {2, 18 * kG}}, 50 * kG);
  EXPECT_DOUBLE_EQ(curve.at(2), 18 * kG);
  EXPECT_NEAR(curve.at(4), 1800.0 / 68.0 * kG, 1e-6 * kG);    // 26.47 GB/s
  EXPECT_NEAR(curve.at(16), 7200.0 / 176.0 * kG, 1e-6 * kG);  // 40.91 GB/s
  EXPECT_LT(curve.at(1000), 50 * kG);
  EXPECT_GT(curve.at(1000), 49.8 * kG);
  for (int p = 2; p < 64; ++p) EXPECT_LT(curve.at(p), curve.at(p + 1)) << p;
}

TEST(BandwidthCurve, ACeilingBelowTheMeasuredPointIsTheMeasuredPoint) {
  const BandwidthCurve curve({{1, 10 * kG}, {2, 18 * kG}}, 15 * kG);
  EXPECT_DOUBLE_EQ(curve.at(8), 18 * kG);
}

TEST(BandwidthCurve, BadCurvesAreRefusedWithTheReason) {
  EXPECT_THROW(BandwidthCurve({}, 0.0), std::invalid_argument);
  EXPECT_THROW(BandwidthCurve({{0, kG}}, 0.0), std::invalid_argument);
  EXPECT_THROW(BandwidthCurve({{2, kG}, {1, kG}}, 0.0), std::invalid_argument);
  EXPECT_THROW(BandwidthCurve({{1, kG}, {1, kG}}, 0.0), std::invalid_argument);
  EXPECT_THROW(BandwidthCurve({{1, 0.0}}, 0.0), std::invalid_argument);
  EXPECT_THROW(BandwidthCurve({{1, kG}}, -1.0), std::invalid_argument);
  try {
    const BandwidthCurve curve({{1, kG}, {2, -kG}}, 0.0);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("at 2 threads"), std::string::npos) << e.what();
  }
  EXPECT_THROW(BandwidthCurve({{1, kG}}, 0.0).at(0), std::invalid_argument);
}

TEST(Roofline, TheLongerOfComputeAndTraffic) {
  EXPECT_DOUBLE_EQ(roofline_seconds(1.0, 10 * kG, 5 * kG), 2.0);  // 10 GB at 5 GB/s
  EXPECT_DOUBLE_EQ(roofline_seconds(3.0, 10 * kG, 5 * kG), 3.0);
  EXPECT_DOUBLE_EQ(roofline_seconds(0.5, 0.0, 5 * kG), 0.5);
  EXPECT_THROW(roofline_seconds(-1.0, 1.0, kG), std::invalid_argument);
  EXPECT_THROW(roofline_seconds(1.0, 1.0, 0.0), std::invalid_argument);
}

TEST(WorkingSet, TheSmallestProbedSizeThatHoldsTheFootprint) {
  const std::vector<std::uint64_t> sizes{16u << 20, 64u << 20, 256u << 20};
  EXPECT_EQ(working_set_for(sizes, 1u << 20), 0u);
  EXPECT_EQ(working_set_for(sizes, 16u << 20), 0u);
  EXPECT_EQ(working_set_for(sizes, 46u << 20), 1u);
  EXPECT_EQ(working_set_for(sizes, 300u << 20), 2u) << "beyond every size: the largest";
  EXPECT_THROW(working_set_for({}, 1), std::invalid_argument);
}

}  // namespace
}  // namespace contactlab::tuner
