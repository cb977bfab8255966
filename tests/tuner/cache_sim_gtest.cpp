// Small runs under valgrind's cache simulator: the paper's ordering (reordering cuts the L1
// misses per candidate test, and the miss rate, several-fold for both loops), several threads,
// and failures recorded, not zeros.
#include <gtest/gtest.h>

#include <cstdlib>
#include <string_view>

#include "contactlab/tuner/cache_sim.hpp"
#include "program_test_support.hpp"

namespace contactlab::tuner {
namespace {

// This test program is not beside contactlab-cachesim, as contactlab is: name it.
[[maybe_unused]] const bool kCachesimNamed =
    setenv("CONTACTLAB_CACHESIM", CONTACTLAB_CACHESIM_EXE, 1) == 0;

// One simulated detection of a small clustered scene, as `detect --cache-sim` runs it.
CounterRecord simulate(const std::string& variant, int threads, const CacheGeometry& geometry) {
  const SceneSpec spec = test::small_clustered(3000);
  return simulate_detection_caches(generate_scene(spec), spec.diameter, parse_variant(variant),
                                   threads, geometry);
}

std::uint64_t event_total(const CounterRecord& r, std::string_view name) {
  for (const auto& e : r.events) {
    if (e.name == name) return e.total;
  }
  ADD_FAILURE() << "no event " << name;
  return 0;
}

// L1 misses per candidate test of the simulated run, by its own count of tests.
double l1_misses_per_test(const CounterRecord& r) {
  if (!r.simulation || !r.simulation->candidate_tests || *r.simulation->candidate_tests == 0) {
    ADD_FAILURE() << "the simulated run reported no candidate tests";
    return 0.0;
  }
  return static_cast<double>(event_total(r, "D1mr") + event_total(r, "D1mw")) /
         static_cast<double>(*r.simulation->candidate_tests);
}

// Misses per candidate test compare across codes (a rate's denominator, the accesses per test,
// belongs to the code). The scene is large enough that the coordinate arrays are huge-page
// allocations (N * 8 B >= 2 MiB): when these all began on a 2 MiB boundary, x[i], y[i] and
// z[i] shared one set of the 2-way L1 and the sorted loop missed about 3 times per test, more
// than the unsorted one (docs/measurement.md, Table 6). Sparse (D = 0.005) to stay quick.
TEST(CacheSim, ReorderingCutsL1MissesPerCandidateTestForBothLoops) {
  if (const auto why = test::valgrind_obstacle(); !why.empty()) GTEST_SKIP() << why;
  const SceneSpec spec = test::small_clustered(270000, 0.005);
  const Scene scene = generate_scene(spec);
  for (const std::string loop : {"particle", "cell"}) {
    auto simulated = [&](const std::string& order) {
      return simulate_detection_caches(scene, spec.diameter,
                                       parse_variant(loop + "/" + order + "/full/static"), 1,
                                       fx10_geometry());
    };
    const CounterRecord unsorted = simulated("unsorted");
    const CounterRecord sorted = simulated("sorted");
    ASSERT_TRUE(unsorted.available) << unsorted.reason;
    ASSERT_TRUE(sorted.available) << sorted.reason;
    // The simulated program runs the scalar loop, and says so.
    EXPECT_EQ(sorted.simulation->simd_target, "off");
    // Its tests are the native run's (the unsorted layouts never tile).
    ContactDetector detector;
    const DetectRun native =
        detector.run(scene, {parse_variant(loop + "/unsorted/full/static"), spec.diameter, 1});
    EXPECT_EQ(unsorted.simulation->candidate_tests, native.candidate_tests) << loop;
    const double per_test_unsorted = l1_misses_per_test(unsorted);
    const double per_test_sorted = l1_misses_per_test(sorted);
    EXPECT_GT(per_test_unsorted, 5.0 * per_test_sorted) << loop;
    EXPECT_LT(per_test_sorted, 1.0) << loop << ": the sorted loop misses on most coordinates";
    ASSERT_TRUE(unsorted.l1_miss_percent && sorted.l1_miss_percent);
    EXPECT_GT(*unsorted.l1_miss_percent, 3.0 * *sorted.l1_miss_percent) << loop;
  }
}

TEST(CacheSim, ReorderingCutsTheL1MissRateForBothLoops) {
  if (const auto why = test::valgrind_obstacle(); !why.empty()) GTEST_SKIP() << why;
  for (const std::string loop : {"particle", "cell"}) {
    const CounterRecord unsorted = simulate(loop + "/unsorted/static", 1, fx10_geometry());
    const CounterRecord sorted = simulate(loop + "/sorted/static", 1, fx10_geometry());
    ASSERT_TRUE(unsorted.available) << unsorted.reason;
    ASSERT_TRUE(sorted.available) << sorted.reason;
    EXPECT_EQ(sorted.source, "simulated:fx10");
    ASSERT_TRUE(unsorted.l1_miss_percent && sorted.l1_miss_percent && sorted.l2_miss_percent);
    EXPECT_GT(*unsorted.l1_miss_percent, 3.0 * *sorted.l1_miss_percent) << loop;
    EXPECT_GT(*sorted.l1_miss_percent, 0.0);
    EXPECT_LE(*sorted.l2_miss_percent, *sorted.l1_miss_percent);
    ASSERT_TRUE(sorted.simulation.has_value());
    EXPECT_EQ(sorted.simulation->geometry.name, "fx10");
    EXPECT_EQ(sorted.simulation->code_isa, cachesim_code_isa());
    EXPECT_EQ(sorted.simulation->executable, cachesim_executable());
  }
}

TEST(CacheSim, EveryThreadIsCounted) {
  if (const auto why = test::valgrind_obstacle(); !why.empty()) GTEST_SKIP() << why;
  const CounterRecord one = simulate("particle/sorted/static", 1, fx10_geometry());
  const CounterRecord two = simulate("particle/sorted/static", 2, fx10_geometry());
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
  const CounterRecord r =
      simulate("cell/sorted/static", 1, parse_cache_geometry("custom:16K,4,64:256K,8,64"));
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
  CacheSimRequest r;
  r.geometry = fx10_geometry();
  r.executable = cachesim_executable();
  r.arguments = {"--scene-file", "/nonexistent.bin",
                 "--variant",    "particle/sideways/static",
                 "--threads",    "1"};
  const CounterRecord record = simulate_caches(r);
  EXPECT_FALSE(record.available);
  EXPECT_NE(record.reason.find("exited with status 2"), std::string::npos) << record.reason;
  EXPECT_NE(record.reason.find("sideways"), std::string::npos) << record.reason;
}

// A program valgrind cannot execute (here: one that dies of SIGILL, as a -march=native binary
// with AVX-512 does under valgrind 3.19) is explained in words, not only as a signal number.
TEST(CacheSim, IllegalInstructionIsExplained) {
  if (const auto why = test::valgrind_obstacle(); !why.empty()) GTEST_SKIP() << why;
  CacheSimRequest r;
  r.geometry = fx10_geometry();
  r.executable = "/bin/sh";
  r.arguments = {"-c", "kill -ILL $$"};
  const CounterRecord record = simulate_caches(r);
  EXPECT_FALSE(record.available);
  EXPECT_NE(record.reason.find("valgrind cannot execute this binary's instructions"),
            std::string::npos)
      << record.reason;
}

// The simulated program holds no AVX-512 instruction: no zmm or opmask register, and no EVEX
// register above 15, anywhere in its disassembly (glibc's AVX-512 routines are chosen at run
// time by CPUID, which valgrind answers without AVX-512).
TEST(CacheSim, SimulatedProgramHasNoAvx512Instructions) {
  if (test::run_command("objdump --version").exit_code != 0) {
    GTEST_SKIP() << "objdump (binutils) is not on PATH: cannot disassemble";
  }
  const std::string program = cachesim_executable();
  const auto count =
      test::run_command("objdump -d --no-show-raw-insn " + program +
                        " | grep -cE '%zmm|%k[1-7]|\\{%k|%[xy]mm(1[6-9]|2[0-9]|3[01])\\b'");
  EXPECT_EQ(count.output, "0\n") << program << " contains AVX-512 instructions";
  // Its recorded instruction set is the program's own.
  const auto isa = test::run_command(program + " --print-isa");
  ASSERT_EQ(isa.exit_code, 0) << isa.output;
  EXPECT_EQ(isa.output, cachesim_code_isa() + "\n");
}

TEST(CacheSim, MissingSimulatedProgramIsRecorded) {
  const SceneSpec spec = test::small_clustered(500);
  setenv("CONTACTLAB_CACHESIM", "/nonexistent/contactlab-cachesim", 1);
  const CounterRecord r = simulate_detection_caches(
      generate_scene(spec), spec.diameter, parse_variant("cell/sorted/static"), 1, fx10_geometry());
  setenv("CONTACTLAB_CACHESIM", CONTACTLAB_CACHESIM_EXE, 1);
  EXPECT_FALSE(r.available);
  EXPECT_NE(r.reason.find("/nonexistent/contactlab-cachesim"), std::string::npos) << r.reason;
}

}  // namespace
}  // namespace contactlab::tuner
