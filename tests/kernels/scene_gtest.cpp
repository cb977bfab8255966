// scene.hpp: Box, parse_box, validate_scene, scene_checksum, max_diameter.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>

#include "contactlab/kernels/error.hpp"
#include "test_support.hpp"

namespace contactlab::test {
namespace {

const double kNaN = std::numeric_limits<double>::quiet_NaN();
const double kInf = std::numeric_limits<double>::infinity();

TEST(Box, ContainsIsTheClosedBox) {
  const Box box{{-1, 0, 2}, {1, 0.5, 3}};
  EXPECT_EQ(box.extent(0), 2.0);
  EXPECT_EQ(box.extent(1), 0.5);
  EXPECT_EQ(box.extent(2), 1.0);
  EXPECT_TRUE(box.contains(-1, 0, 2));
  EXPECT_TRUE(box.contains(1, 0.5, 3));
  EXPECT_TRUE(box.contains(0, 0.25, 2.5));
  EXPECT_FALSE(box.contains(std::nextafter(1.0, 2.0), 0.25, 2.5));
  EXPECT_FALSE(box.contains(0, std::nextafter(0.0, -1.0), 2.5));
  EXPECT_FALSE(box.contains(0, 0.25, kNaN));
  const Box unit;
  EXPECT_EQ(unit.lo, (std::array<double, 3>{0, 0, 0}));
  EXPECT_EQ(unit.hi, (std::array<double, 3>{1, 1, 1}));
}

TEST(ParseBox, AcceptsSixNumbers) {
  const Box box = parse_box("-1,0,2.5,1,0.5,3e2");
  EXPECT_EQ(box.lo, (std::array<double, 3>{-1, 0, 2.5}));
  EXPECT_EQ(box.hi, (std::array<double, 3>{1, 0.5, 300}));
}

TEST(ParseBox, RejectsMalformedBoxes) {
  for (const char* text :
       {"", "0,0,0,1,1", "0,0,0,1,1,1,1", "0,0,0,1,1,", ",0,0,1,1,1", "a,0,0,1,1,1", "0,0,0,1,1,1x",
        "nan,0,0,1,1,1", "0,0,0,inf,1,1", "1,0,0,1,1,1", "2,0,0,1,1,1", "0;0;0;1;1;1"}) {
    EXPECT_THROW(parse_box(text), InputError) << "'" << text << "'";
  }
}

TEST(ValidateScene, AcceptsPointsOnTheClosedBox) {
  const Scene scene = make_scene({{0, 0, 0}, {1, 1, 1}, {0.5, 1, 0}}, Box{});
  EXPECT_NO_THROW(validate_scene(scene, "s"));
  EXPECT_NO_THROW(validate_scene(Scene{}, "empty"));
}

TEST(ValidateScene, RejectsBadScenesNamingTheSource) {
  auto expect_throw = [](const Scene& scene, const std::string& what) {
    try {
      validate_scene(scene, "the-source.csv");
      ADD_FAILURE() << what << ": no exception";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("the-source.csv"), std::string::npos)
          << what << ": " << e.what();
    }
  };
  Scene ok = make_scene({{0.5, 0.5, 0.5}, {0.25, 0.25, 0.25}});
  {
    Scene s = ok;
    s.x[1] = kNaN;
    expect_throw(s, "NaN");
  }
  {
    Scene s = ok;
    s.z[0] = kInf;
    expect_throw(s, "inf");
  }
  {
    Scene s = ok;
    s.y[0] = 1.5;
    expect_throw(s, "outside");
  }
  {
    Scene s = ok;
    s.x[0] = -1e-300;
    expect_throw(s, "just below");
  }
  {
    Scene s = ok;
    s.diameter = {0.1, 0.0};
    expect_throw(s, "zero diameter");
  }
  {
    Scene s = ok;
    s.diameter = {-0.1, 0.1};
    expect_throw(s, "negative diameter");
  }
  {
    Scene s = ok;
    s.diameter = {0.1, kNaN};
    expect_throw(s, "NaN diameter");
  }
  {
    Scene s = ok;
    s.diameter = {0.1};
    expect_throw(s, "short diameter array");
  }
  {
    Scene s = ok;
    s.y.pop_back();
    expect_throw(s, "short y array");
  }
  {
    Scene s = ok;
    s.box = Box{{0, 0, 0}, {1, 1, 0}};
    expect_throw(s, "flat box");
  }
  {
    Scene s = ok;
    s.box = Box{{0, 0, 0}, {kInf, 1, 1}};
    expect_throw(s, "infinite box");
  }
}

TEST(SceneChecksum, EqualExactlyForBitIdenticalScenes) {
  SceneSpec spec;
  spec.kind = SceneKind::kPolydisperse;
  spec.n = 100;
  const Scene a = generate_scene(spec);
  // NOLINTNEXTLINE(performance-unnecessary-copy-initialization): the copy is the point
  const Scene b = a;
  EXPECT_EQ(scene_checksum(a), scene_checksum(b));
  // One bit anywhere changes it: a coordinate, a diameter, the box, and -0.0 versus 0.0.
  auto flip = [](double v) {
    std::uint64_t bits;
    std::memcpy(&bits, &v, 8);
    bits ^= 1;
    std::memcpy(&v, &bits, 8);
    return v;
  };
  Scene c = a;
  c.z[57] = flip(c.z[57]);
  EXPECT_NE(scene_checksum(a), scene_checksum(c));
  c = a;
  c.diameter[99] = flip(c.diameter[99]);
  EXPECT_NE(scene_checksum(a), scene_checksum(c));
  c = a;
  c.box.hi[2] = flip(c.box.hi[2]);
  EXPECT_NE(scene_checksum(a), scene_checksum(c));
  const Scene zero = make_scene({{0.0, 0.5, 0.5}});
  const Scene negative_zero = make_scene({{-0.0, 0.5, 0.5}});
  EXPECT_NE(scene_checksum(zero), scene_checksum(negative_zero));
  // Swapping two particles is a different scene.
  c = a;
  std::swap(c.x[0], c.x[1]);
  std::swap(c.y[0], c.y[1]);
  std::swap(c.z[0], c.z[1]);
  std::swap(c.diameter[0], c.diameter[1]);
  EXPECT_NE(scene_checksum(a), scene_checksum(c));
}

TEST(SceneChecksum, EmptySceneIsTheHashOfTheBox) {
  Scene a, b;
  EXPECT_EQ(scene_checksum(a), scene_checksum(b));
  b.box.hi[0] = 2.0;
  EXPECT_NE(scene_checksum(a), scene_checksum(b));
}

TEST(Scene, MaxDiameter) {
  Scene scene = make_scene({{0, 0, 0}, {1, 1, 1}, {0.5, 0.5, 0.5}});
  EXPECT_FALSE(scene.has_diameters());
  EXPECT_EQ(scene.max_diameter(), 0.0);
  scene.diameter = {0.1, 0.3, 0.2};
  EXPECT_TRUE(scene.has_diameters());
  EXPECT_EQ(scene.max_diameter(), 0.3);
  EXPECT_EQ(scene.size(), 3u);
}

}  // namespace
}  // namespace contactlab::test
