// The bytes of a detection (tuner_model/detection_traffic.hpp) on hand-computed cases: the
// candidates a loop fetches, and every phase's bytes for the sorted and unsorted orders, both
// stencils and both precisions.
#include <gtest/gtest.h>

#include <stdexcept>
#include <vector>

#include "contactlab/tuner_model/detection_traffic.hpp"

namespace contactlab::tuner {
namespace {

Variant variant(Order order, Stencil stencil, Precision precision = Precision::kDouble) {
  Variant v;
  v.order = order;
  v.stencil = stencil;
  v.precision = precision;
  return v;
}

TEST(CandidateFetches, ACellsHomesShareItsCandidates) {
  // Three cells of 4, 0 and 2 homes testing 40, 0 and 10 pairs: 10 + 0 + 5 candidates.
  const std::vector<std::uint32_t> tests{40, 0, 10}, homes{4, 0, 2};
  const std::vector<std::uint8_t> builds{1, 0, 1};
  EXPECT_EQ(candidate_fetches(WorkView{tests, homes, builds}), 15u);
  // A particle loop: every test fetches its candidate.
  EXPECT_EQ(candidate_fetches(WorkView(tests)), 50u);
}

// 1000 particles, 5000 fetches, 600 entries, 4096 keys (12 bits: two radix passes).
constexpr DetectionWork kWork{1000, 5000, 600, 4096, false};

TEST(DetectionTraffic, SortedStreamsItsRecordsOnce) {
  const DetectionTraffic t = detection_traffic(variant(Order::kSorted, Stencil::kFull), kWork);
  // Registration: 1000 (24 + 8) + 2 passes x 2 x 8 x 1000 + 4 x 4096; the gather 1000 (3 x 64
  // + 24 + 4): a scene this small is read where it is.
  EXPECT_DOUBLE_EQ(t.setup_bytes, 32000.0 + 32000.0 + 16384.0 + 220000.0);
  // The loop: the records once (24 000), the cell index (16 384), the 600 finds (2 400).
  EXPECT_DOUBLE_EQ(t.loop_bytes, 24000.0 + 16384.0 + 2400.0);
  EXPECT_DOUBLE_EQ(t.rows_bytes, 4.0 * 600 + 4.0 * 600);
  EXPECT_DOUBLE_EQ(t.offsets_bytes, 8000.0);
  EXPECT_EQ(t.footprint_bytes, 24000u + 16384u);
}

TEST(DetectionTraffic, UnsortedFetchesALinePerArrayAndCandidate) {
  const DetectionTraffic t = detection_traffic(variant(Order::kUnsorted, Stencil::kFull), kWork);
  // The slot maps: 1000 x 8 (no copy of so small a scene).
  EXPECT_DOUBLE_EQ(t.setup_bytes, 32000.0 + 32000.0 + 16384.0 + 8000.0);
  // 5000 fetches of 3 lines and an id, 1000 homes of 3 lines, the cell index, the finds.
  EXPECT_DOUBLE_EQ(t.loop_bytes, 5000.0 * 196 + 1000.0 * 192 + 16384.0 + 2400.0);
  EXPECT_EQ(t.footprint_bytes, 1000u * 32 + 16384u);
}

TEST(DetectionTraffic, HalfStencilFloatAndDiameters) {
  DetectionWork work = kWork;
  work.diameters = true;
  const DetectionTraffic t =
      detection_traffic(variant(Order::kMorton, Stencil::kHalf, Precision::kFloat), work);
  // Four arrays: the input record 32 bytes, the float record 16; the half stencil finds 300.
  EXPECT_DOUBLE_EQ(t.setup_bytes, 1000.0 * 40 + 32000.0 + 16384.0 + 1000.0 * (4 * 64 + 16 + 4));
  EXPECT_DOUBLE_EQ(t.loop_bytes, 16000.0 + 16384.0 + 1200.0);
  EXPECT_DOUBLE_EQ(t.rows_bytes, 1200.0 + 2400.0);
  EXPECT_DOUBLE_EQ(t.offsets_bytes, 16000.0) << "the reverse counts too";
}

// Past 4 MiB of coordinate arrays the kernels copy before reading at random: the sorted orders
// gather one line of a 32-byte staged record a particle, the unsorted double loop copies the
// coordinates (24 bytes a particle written).
TEST(DetectionTraffic, LargeScenesAreReadAtRandomFromCopies) {
  DetectionWork work = kWork;
  work.particles = 1'000'000;  // 24 MB of arrays
  const double n = 1e6;
  const DetectionTraffic sorted = detection_traffic(variant(Order::kSorted, Stencil::kFull), work);
  const DetectionTraffic unsorted =
      detection_traffic(variant(Order::kUnsorted, Stencil::kFull), work);
  // Registration as above, per particle; the gather 32 + 64 bytes instead of 3 x 64.
  EXPECT_DOUBLE_EQ(sorted.setup_bytes, n * 32 + 2 * 2 * 8 * n + 16384.0 + n * (32 + 64 + 24 + 4));
  EXPECT_DOUBLE_EQ(unsorted.setup_bytes, n * 32 + 2 * 2 * 8 * n + 16384.0 + n * (8 + 24));
}

TEST(DetectionTraffic, ARadixPassPerEightBitsOfKey) {
  DetectionWork work = kWork;
  work.cell_keys = std::uint64_t{200} * 200 * 200;  // 23 bits: three passes
  const double three =
      detection_traffic(variant(Order::kUnsorted, Stencil::kFull), work).setup_bytes;
  work.cell_keys = std::uint64_t{504} * 504 * 504;  // 27 bits: four
  const double four =
      detection_traffic(variant(Order::kUnsorted, Stencil::kFull), work).setup_bytes;
  EXPECT_DOUBLE_EQ(four - three, 16000.0 + 4.0 * (504.0 * 504 * 504 - 200.0 * 200 * 200));
}

TEST(DetectionTraffic, NoParticlesOrNoKeysIsRefused) {
  EXPECT_THROW(detection_traffic(Variant{}, DetectionWork{0, 1, 1, 8, false}),
               std::invalid_argument);
  EXPECT_THROW(detection_traffic(Variant{}, DetectionWork{8, 1, 1, 0, false}),
               std::invalid_argument);
}

}  // namespace
}  // namespace contactlab::tuner
