// The PNG pictures (built with cairo): a section slab and the discharge plot are valid PNG files
// of the announced size, written atomically; the initial-height bands split the particles evenly.
#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "contactlab/dem/picture.hpp"
#include "dem_support.hpp"

namespace contactlab::dem {
namespace {

std::vector<unsigned char> bytes_of(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// PNG signature, then the IHDR chunk: width and height big-endian at bytes 16 and 20.
void expect_png(const std::string& path, int width, int height) {
  const std::vector<unsigned char> b = bytes_of(path);
  ASSERT_GT(b.size(), 33u) << path;
  const unsigned char signature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  for (int k = 0; k < 8; ++k) EXPECT_EQ(b[k], signature[k]) << path;
  EXPECT_EQ(std::string(b.begin() + 12, b.begin() + 16), "IHDR");
  auto be32 = [&](int at) {
    return static_cast<int>(std::uint32_t{b[at]} << 24 | std::uint32_t{b[at + 1]} << 16 |
                            std::uint32_t{b[at + 2]} << 8 | std::uint32_t{b[at + 3]});
  };
  EXPECT_EQ(be32(16), width);
  EXPECT_EQ(be32(20), height);
}

TEST(DemPicture, HeightBandsHaveEqualCounts) {
  auto [settings, particles] = test::small_bed(160);
  const std::vector<std::uint8_t> bands = height_layers(particles, 8);
  ASSERT_EQ(bands.size(), 160u);
  std::vector<int> count(8, 0);
  for (std::uint8_t b : bands) ++count[b];
  for (int c : count) EXPECT_EQ(c, 20);
  // The lowest particle is in band 0, the highest in band 7.
  std::size_t low = 0, high = 0;
  for (std::size_t a = 0; a < particles.size(); ++a) {
    if (particles.z[a] < particles.z[low]) low = a;
    if (particles.z[a] > particles.z[high]) high = a;
  }
  EXPECT_EQ(bands[particles.id[low]], 0);
  EXPECT_EQ(bands[particles.id[high]], 7);
}

TEST(DemPicture, SectionAndDischargePlotAreValidPngs) {
  auto [settings, particles] = test::small_bed();  // its floor is drawn as a gate (dashed)
  SectionView view = section_view_for(settings, particles);
  view.plot_width_px = 300;
  EXPECT_DOUBLE_EQ(view.axis_y, 0.005);
  const std::string dir = ::testing::TempDir();
  SectionPainter painter(dir, "bed", view, height_layers(particles, view.layers));
  Engine engine(settings, particles);
  engine.run_steps(20);
  painter.write(engine.snapshot(), 2);
  EXPECT_EQ(painter.frame_path(2), dir + (dir.back() == '/' ? "" : "/") + "bed_section_00002.png");
  EXPECT_EQ(painter.width(), 70 + 300 + 170);
  // The 10 x 50 mm window at 300 px across: 1500 px of plot, plus the margins.
  EXPECT_EQ(painter.height(), 40 + 1500 + 50);
  expect_png(painter.frame_path(2), painter.width(), painter.height());

  std::vector<DischargeRow> rows;
  for (int k = 0; k <= 10; ++k) rows.push_back({0.01 * k, 0, 1e-3 * k * k, 0, 0});
  const std::string plot = dir + "/discharge.png";
  write_discharge_plot(plot, rows, "test");
  expect_png(plot, 800, 500);
  write_discharge_plot(plot, {}, "no rows");  // an empty series still draws its axes
  expect_png(plot, 800, 500);
}

}  // namespace
}  // namespace contactlab::dem
