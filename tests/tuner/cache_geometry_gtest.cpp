// Cache geometries (named, custom, invalid) and the callgrind output parser.
#include <gtest/gtest.h>

#include <fstream>

#include "contactlab/kernels/error.hpp"
#include "contactlab/tuner/cache_sim.hpp"
#include "contactlab/tuner/context.hpp"
#include "program_test_support.hpp"

namespace contactlab::tuner {
namespace {

std::string error_of(const std::string& text) {
  try {
    parse_cache_geometry(text);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(CacheGeometry, Fx10IsTheCitedSparc64IXfx) {
  const CacheGeometry g = parse_cache_geometry("fx10");
  EXPECT_EQ(g.l1.size_bytes, 32u * 1024);
  EXPECT_EQ(g.l1.associativity, 2);
  EXPECT_EQ(g.l1.line_bytes, 128);
  EXPECT_EQ(g.l1.sets(), 128u);
  EXPECT_EQ(g.l2.size_bytes, 12u * 1024 * 1024);
  EXPECT_EQ(g.l2.associativity, 24);
  EXPECT_EQ(g.l2.sets(), 4096u);
  EXPECT_TRUE(g.approximation);
  EXPECT_NE(g.description.find("approximation"), std::string::npos);
}

TEST(CacheGeometry, CustomWithSuffixes) {
  const CacheGeometry g = parse_cache_geometry("custom:48K,12,64:2M,16,64");
  EXPECT_EQ(g.name, "custom");
  EXPECT_EQ(g.l1.size_bytes, 48u * 1024);
  EXPECT_EQ(g.l1.sets(), 64u);
  EXPECT_EQ(g.l2.size_bytes, 2u * 1024 * 1024);
  EXPECT_EQ(g.l2.sets(), 2048u);
}

TEST(CacheGeometry, RejectsSetCountsThatAreNotPowersOfTwo) {
  // 48 KiB / (8 ways * 64 B) = 96 sets.
  const std::string e = error_of("custom:48K,8,64:1M,16,64");
  EXPECT_NE(e.find("L1"), std::string::npos) << e;
  EXPECT_NE(e.find("not a power of two"), std::string::npos) << e;
  // 12 MiB / (16 * 64) = 12288 sets.
  EXPECT_NE(error_of("custom:32K,8,64:12M,16,64").find("L2"), std::string::npos);
}

TEST(CacheGeometry, RejectsOtherBadGeometries) {
  EXPECT_NE(error_of("custom:32K,8,48:1M,16,64").find("line size"), std::string::npos);
  EXPECT_NE(error_of("custom:32K,8,8:1M,16,8").find("line size"), std::string::npos);
  EXPECT_NE(error_of("custom:32K,0,64:1M,16,64").find("associativity"), std::string::npos);
  EXPECT_NE(error_of("custom:1M,16,64:32K,8,64").find("smaller than L1"), std::string::npos);
  EXPECT_NE(error_of("custom:32K,8,64").find("expected custom:"), std::string::npos);
  EXPECT_NE(error_of("custom:32Q,8,64:1M,16,64").find("not a size"), std::string::npos);
  EXPECT_NE(error_of("custom:32K,8:1M,16,64").find("SIZE,WAYS,LINE"), std::string::npos);
  EXPECT_NE(error_of("sparc").find("unknown cache geometry 'sparc'"), std::string::npos);
  EXPECT_NE(error_of("").find("unknown cache geometry"), std::string::npos);
}

TEST(CacheGeometry, HostIsReadOrRefusedClearly) {
  try {
    const CacheGeometry g = parse_cache_geometry("host");
    EXPECT_EQ(g.name, "host");
    EXPECT_GT(g.l1.size_bytes, 0u);
    EXPECT_GE(g.l2.size_bytes, g.l1.size_bytes);
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("host"), std::string::npos);
  }
}

TEST(CallgrindTotals, ParsesEventsAndTotals) {
  test::TempDir dir;
  const std::string path = dir.file("callgrind.out");
  std::ofstream(path) << "# callgrind format\nversion: 1\ncreator: callgrind-3.19.0\n"
                         "events: Ir Dr Dw I1mr D1mr D1mw ILmr DLmr DLmw\n"
                         "fn=(1) main\n5 1 2 3\n"
                         "summary: 100 40 10 1 8 2 1 3\n"
                         "totals: 100 40 10 1 8 2 1 3 1\n";
  const CallgrindTotals t = read_callgrind_totals(path);
  EXPECT_EQ(t.get("Ir"), 100u);
  EXPECT_EQ(t.get("D1mr"), 8u);
  EXPECT_EQ(t.get("DLmw"), 1u);
  EXPECT_THROW(t.get("Bc"), InputError);

  std::ofstream(path, std::ios::trunc) << "events: Ir Dr\nsummary: 7\n";  // trailing zeros omitted
  const CallgrindTotals s = read_callgrind_totals(path);
  EXPECT_EQ(s.get("Dr"), 0u);

  std::ofstream(path, std::ios::trunc) << "version: 1\ntotals: 1 2\n";
  EXPECT_THROW(read_callgrind_totals(path), InputError);
  std::ofstream(path, std::ios::trunc) << "events: Ir\ntotals: x\n";
  EXPECT_THROW(read_callgrind_totals(path), InputError);
  EXPECT_THROW(read_callgrind_totals(dir.file("absent")), InputError);
}

TEST(SimulateCaches, MissingValgrindIsRecordedNotThrown) {
  CacheSimRequest request;
  request.geometry = fx10_geometry();
  request.executable = "/bin/true";
  request.valgrind = "/nonexistent/valgrind";
  const CounterRecord r = simulate_caches(request);
  EXPECT_EQ(r.source, "simulated:fx10");
  EXPECT_FALSE(r.available);
  EXPECT_NE(r.reason.find("/nonexistent/valgrind"), std::string::npos) << r.reason;
  EXPECT_FALSE(r.l1_miss_percent.has_value());
  EXPECT_FALSE(r.l2_miss_percent.has_value());
  ASSERT_TRUE(r.simulation.has_value());
  EXPECT_TRUE(r.simulation->geometry.approximation);
}

TEST(SimulateCaches, InvalidGeometryThrows) {
  CacheSimRequest request;
  request.geometry = fx10_geometry();
  request.geometry.l2.associativity = 20;  // 12 MiB / (20 * 128) is not a whole power of two
  request.executable = "/bin/true";
  EXPECT_THROW(simulate_caches(request), InputError);
}

TEST(MachineInfo, DescribesThisMachine) {
  const MachineInfo& m = machine_info();
  EXPECT_GE(m.cores, 1);
  EXPECT_GE(m.pus, m.cores);
  EXPECT_FALSE(m.cpu_model.empty());
  EXPECT_FALSE(m.topology_source.empty());
}

TEST(Context, WarnsAboutOversubscription) {
  const Context c = collect_context("test", machine_info().cores * 4);
  bool warned = false;
  for (const auto& w : c.warnings) warned |= w.find("more threads than cores") != std::string::npos;
  EXPECT_TRUE(warned);
  const Context fine = collect_context("test", 1);
  for (const auto& w : fine.warnings)
    EXPECT_EQ(w.find("more threads than cores"), std::string::npos);
}

}  // namespace
}  // namespace contactlab::tuner
