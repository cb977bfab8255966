// Small runs under valgrind's cache simulator: the paper's ordering (reordering cuts the L1
// miss rate several-fold for both loops), several threads, and failures recorded, not zeros.
#include <gtest/gtest.h>

#include "contactlab/tuner/cache_sim.hpp"
#include "tuner_test_support.hpp"

namespace contactlab::tuner {
namespace {

CacheSimRequest child_request(const std::string& variant, int threads,
                              const CacheGeometry& geometry) {
  CacheSimRequest r;
  r.geometry = geometry;
  r.executable = test::contactlab_exe();
  r.arguments = {"detect",
                 "--scene",
                 "clustered",
                 "--n",
                 "3000",
                 "--diameter",
                 "0.02",
                 "--seed",
                 "7",
                 "--variant",
                 variant,
                 "--threads",
                 std::to_string(threads),
                 "--cache-sim-child"};
  r.threads = threads;
  return r;
}

TEST(CacheSim, ReorderingCutsTheL1MissRateForBothLoops) {
  if (const auto why = test::valgrind_obstacle(); !why.empty()) GTEST_SKIP() << why;
  for (const std::string loop : {"particle", "cell"}) {
    const CounterRecord unsorted =
        simulate_caches(child_request(loop + "/unsorted/static", 1, fx10_geometry()));
    const CounterRecord sorted =
        simulate_caches(child_request(loop + "/sorted/static", 1, fx10_geometry()));
    ASSERT_TRUE(unsorted.available) << unsorted.reason;
    ASSERT_TRUE(sorted.available) << sorted.reason;
    EXPECT_EQ(sorted.source, "simulated:fx10");
    ASSERT_TRUE(unsorted.l1_miss_percent && sorted.l1_miss_percent && sorted.l2_miss_percent);
    EXPECT_GT(*unsorted.l1_miss_percent, 3.0 * *sorted.l1_miss_percent) << loop;
    EXPECT_GT(*sorted.l1_miss_percent, 0.0);
    EXPECT_LE(*sorted.l2_miss_percent, *sorted.l1_miss_percent);
    ASSERT_TRUE(sorted.simulation.has_value());
    EXPECT_EQ(sorted.simulation->geometry.name, "fx10");
  }
}

TEST(CacheSim, EveryThreadIsCounted) {
  if (const auto why = test::valgrind_obstacle(); !why.empty()) GTEST_SKIP() << why;
  const CounterRecord one =
      simulate_caches(child_request("particle/sorted/static", 1, fx10_geometry()));
  const CounterRecord two =
      simulate_caches(child_request("particle/sorted/static", 2, fx10_geometry()));
  ASSERT_TRUE(one.available) << one.reason;
  ASSERT_TRUE(two.available) << two.reason;
  auto reads = [](const CounterRecord& r) {
    for (const auto& e : r.events) {
      if (e.name == "Dr") return e.total;
    }
    return std::uint64_t{0};
  };
  // The same work split over two threads: if only one thread were collected, about half the
  // reads would be missing.
  EXPECT_GT(static_cast<double>(reads(two)), 0.9 * static_cast<double>(reads(one)));
  bool noted = false;
  for (const auto& n : two.notes) noted |= n.find("ONE simulated cache") != std::string::npos;
  EXPECT_TRUE(noted);
}

TEST(CacheSim, CustomGeometry) {
  if (const auto why = test::valgrind_obstacle(); !why.empty()) GTEST_SKIP() << why;
  const CounterRecord r = simulate_caches(
      child_request("cell/sorted/static", 1, parse_cache_geometry("custom:16K,4,64:256K,8,64")));
  ASSERT_TRUE(r.available) << r.reason;
  EXPECT_EQ(r.source, "simulated:custom");
}

TEST(CacheSim, ProgramWithoutTheToggleIsRecordedAsUnavailable) {
  if (const auto why = test::valgrind_obstacle(); !why.empty()) GTEST_SKIP() << why;
  CacheSimRequest r;
  r.geometry = fx10_geometry();
  r.executable = "/bin/true";
  const CounterRecord record = simulate_caches(r);
  EXPECT_FALSE(record.available);
  EXPECT_NE(record.reason.find("no data accesses were collected"), std::string::npos)
      << record.reason;
  EXPECT_FALSE(record.l1_miss_percent.has_value());
}

TEST(CacheSim, FailingChildIsRecordedWithItsMessage) {
  if (const auto why = test::valgrind_obstacle(); !why.empty()) GTEST_SKIP() << why;
  CacheSimRequest r = child_request("particle/sideways/static", 1, fx10_geometry());
  const CounterRecord record = simulate_caches(r);
  EXPECT_FALSE(record.available);
  EXPECT_NE(record.reason.find("exited with status 2"), std::string::npos) << record.reason;
  EXPECT_NE(record.reason.find("sideways"), std::string::npos) << record.reason;
}

}  // namespace
}  // namespace contactlab::tuner
