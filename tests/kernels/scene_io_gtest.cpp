// Scene files: text and binary round trips, the text format's options, and every rejected input
// (the message names the file and, for text, the line).
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>

#include "contactlab/kernels/error.hpp"
#include "contactlab/kernels/scene_io.hpp"
#include "test_support.hpp"

namespace contactlab::test {
namespace {

Scene generated(SceneKind kind, std::uint64_t n, std::uint64_t seed) {
  SceneSpec spec;
  spec.kind = kind;
  spec.n = n;
  spec.seed = seed;
  spec.diameter = 0.01;
  return generate_scene(spec);
}

void expect_same_scene(const Scene& got, const Scene& want) {
  EXPECT_EQ(got.box.lo, want.box.lo);
  EXPECT_EQ(got.box.hi, want.box.hi);
  EXPECT_EQ(got.x, want.x);
  EXPECT_EQ(got.y, want.y);
  EXPECT_EQ(got.z, want.z);
  EXPECT_EQ(got.diameter, want.diameter);
  EXPECT_EQ(scene_checksum(got), scene_checksum(want));
}

// Reads `text` from a file and expects InputError whose message names the file and, when
// `line` > 0, "file:line".
void expect_text_error(const std::string& text, int line, const std::string& what,
                       const Box& box = Box{}) {
  TempDir dir;
  const std::string path = dir.file("bad.csv");
  write_text(path, text);
  for (int reader = 0; reader < 2; ++reader) {
    try {
      if (reader == 0) {
        read_scene(path, box);
      } else {
        read_text_scene(path, box);
      }
      ADD_FAILURE() << what << ": accepted";
    } catch (const InputError& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find(path), std::string::npos) << what << ": " << message;
      if (line > 0) {
        EXPECT_NE(message.find(path + ":" + std::to_string(line)), std::string::npos)
            << what << ": message does not name line " << line << ": " << message;
      }
    }
  }
}

TEST(SceneIo, TextRoundTripIsExact) {
  TempDir dir;
  for (const auto kind : {SceneKind::kClustered, SceneKind::kPolydisperse}) {
    const Scene scene = generated(kind, 2000, 17);
    const std::string path = dir.file("scene.csv");
    write_text_scene(scene, path);
    expect_same_scene(read_scene(path, scene.box), scene);
    expect_same_scene(read_text_scene(path, scene.box), scene);
  }
  // Extreme but valid values survive: denormals, upper faces, a non-unit box.
  Scene odd = make_scene({{0.0, 1e-310, 4.9e-324}, {2.0, 3.0, -1.0}, {1.0 / 3.0, 0.1, -0.0}},
                         Box{{0, 0, -1}, {2, 3, 1}});
  const std::string path = dir.file("odd.csv");
  write_text_scene(odd, path);
  expect_same_scene(read_scene(path, odd.box), odd);
}

TEST(SceneIo, BinaryRoundTripIsBitIdentical) {
  TempDir dir;
  for (const auto kind : all_scene_kinds()) {
    Scene scene = generated(kind, 1500, 23);
    scene.box = Box{{-1, 0, 0}, {1, 1, 1}};  // the box travels in the file
    const std::string path = dir.file("scene.bin");
    write_binary_scene(scene, path);
    expect_same_scene(read_scene(path, Box{}), scene);
    expect_same_scene(read_binary_scene(path), scene);
    // Size per docs: header 72 bytes, then 3 or 4 arrays of N doubles.
    const std::uint64_t arrays = scene.has_diameters() ? 4 : 3;
    EXPECT_EQ(std::filesystem::file_size(path), 72 + arrays * 8 * scene.size());
  }
}

TEST(SceneIo, BinaryHeaderLayout) {
  TempDir dir;
  Scene scene = make_scene({{0.25, 0.5, 0.75}, {1.0, 0.0, 0.5}}, Box{{0, 0, 0}, {1, 1, 1}});
  scene.diameter = {0.1, 0.2};
  const std::string path = dir.file("s.bin");
  write_binary_scene(scene, path);
  const std::string bytes = read_text(path);
  ASSERT_EQ(bytes.size(), 72u + 4 * 8 * 2);
  EXPECT_EQ(bytes.substr(0, 8), "CLSCENE1");
  std::uint32_t version, flags;
  std::uint64_t n;
  double first_x, last_d;
  std::memcpy(&version, bytes.data() + 8, 4);
  std::memcpy(&flags, bytes.data() + 12, 4);
  std::memcpy(&n, bytes.data() + 16, 8);
  std::memcpy(&first_x, bytes.data() + 72, 8);
  std::memcpy(&last_d, bytes.data() + bytes.size() - 8, 8);
  EXPECT_EQ(version, 1u);
  EXPECT_EQ(flags, 1u);
  EXPECT_EQ(n, 2u);
  EXPECT_EQ(first_x, 0.25);
  EXPECT_EQ(last_d, 0.2);
}

TEST(SceneIo, EmptyScenesRoundTrip) {
  TempDir dir;
  const Scene empty;
  write_binary_scene(empty, dir.file("e.bin"));
  EXPECT_EQ(read_scene(dir.file("e.bin"), Box{}).size(), 0u);
  write_text_scene(empty, dir.file("e.csv"));
  EXPECT_EQ(read_scene(dir.file("e.csv"), Box{}).size(), 0u);
}

TEST(SceneIo, EmptyTextFileIsAnEmptyScene) {
  TempDir dir;
  for (const char* text : {"", "\n", "# only a comment\n\n   \n", "x,y,z\n", "# c\nx y z d\n"}) {
    const std::string path = dir.file("empty.csv");
    write_text(path, text);
    const Scene scene = read_scene(path, Box{{0, 0, 0}, {2, 2, 2}});
    EXPECT_EQ(scene.size(), 0u) << "'" << text << "'";
    EXPECT_FALSE(scene.has_diameters());
    EXPECT_EQ(scene.box.hi[0], 2.0);
  }
}

TEST(SceneIo, TextFormatVariations) {
  TempDir dir;
  const Scene want = make_scene({{0.1, 0.2, 0.3}, {1.0, 0.0, 0.5}, {0.25, 0.75, 1.0}});
  const std::vector<std::string> texts = {
      "0.1,0.2,0.3\n1,0,0.5\n0.25,0.75,1\n",            // commas, no header
      "x,y,z\n0.1,0.2,0.3\n1,0,0.5\n0.25,0.75,1\n",     // header
      "0.1 0.2 0.3\n1 0 0.5\n0.25 0.75 1\n",            // spaces
      "x y z\n0.1\t0.2   0.3\n  1 0 0.5\n0.25 0.75 1",  // tabs, no final newline
      "# comment\n\nx, y, z\n# another\n0.1, 0.2 ,0.3\n\n1,0,0.5\r\n0.25,0.75,1\n",  // spaces, CRLF
      "#x,y,z\n   # indented comment\n0.1,0.2,0.3\n1e0,0e0,5e-1\n0.25,0.75,1.0\n",
  };
  for (const auto& text : texts) {
    const std::string path = dir.file("s.txt");
    write_text(path, text);
    SCOPED_TRACE(text);
    expect_same_scene(read_scene(path, Box{}), want);
  }
}

TEST(SceneIo, FourthColumnIsTheDiameter) {
  TempDir dir;
  Scene want = make_scene({{0.1, 0.2, 0.3}, {1.0, 0.0, 0.5}});
  want.diameter = {0.01, 0.02};
  for (const std::string text :
       {"x,y,z,d\n0.1,0.2,0.3,0.01\n1,0,0.5,0.02\n", "0.1 0.2 0.3 0.01\n1 0 0.5 0.02\n"}) {
    const std::string path = dir.file("d.csv");
    write_text(path, text);
    expect_same_scene(read_scene(path, Box{}), want);
  }
}

TEST(SceneIo, TextIsValidatedAgainstTheGivenBox) {
  TempDir dir;
  const std::string path = dir.file("s.csv");
  write_text(path, "-0.5,2,3\n");
  const Box box{{-1, 0, 0}, {0, 2, 3}};
  const Scene scene = read_scene(path, box);
  EXPECT_EQ(scene.size(), 1u);
  EXPECT_EQ(scene.box.lo, box.lo);
  EXPECT_EQ(scene.box.hi, box.hi);
  expect_text_error("-0.5,2,3\n", 1, "outside the unit box");
}

TEST(SceneIo, BadTextInputsNameFileAndLine) {
  expect_text_error("0.1,0.2,0.3\nnan,0.2,0.3\n", 2, "NaN");
  expect_text_error("0.1,0.2,0.3\n0.1,NaN,0.3\n", 2, "NaN spelled differently");
  expect_text_error("# c\n0.1,0.2,inf\n", 2, "inf");
  expect_text_error("0.1,0.2,-inf\n", 1, "-inf");
  expect_text_error("0.1,0.2,1e400\n", 1, "overflow to inf");
  expect_text_error("0.1,0.2,0.3,nan\n", 1, "NaN diameter");
  expect_text_error("x,y,z\n0.1,0.2,0.3\n0.5,1.5,0.5\n", 3, "outside the box");
  expect_text_error("0.1,0.2,-0.3\n", 1, "negative coordinate");
  expect_text_error("0.1,0.2,0.3\n0.1,0.2,abc\n", 2, "malformed number");
  expect_text_error("0.1,0.2,0.3\n0.1;0.2;0.3\n", 2, "wrong separator");
  expect_text_error("0.1,0.2,0.3\n0.1,0.2,0.3x\n", 2, "trailing garbage");
  expect_text_error("0.1,0.2,0.3\n0.1,0.2,\n", 2, "empty field");
  expect_text_error("0.1,0.2,0.3\n0.1,,0.3\n", 2, "empty middle field");
  expect_text_error("0.1,0.2\n", 1, "two columns");
  expect_text_error("0.1,0.2,0.3,0.4,0.5\n", 1, "five columns");
  expect_text_error("0.1,0.2,0.3\n0.1,0.2,0.3,0.01\n", 2, "column count changes 3 -> 4");
  expect_text_error("0.1,0.2,0.3,0.01\n\n0.1,0.2,0.3\n", 3, "column count changes 4 -> 3");
  expect_text_error("x,y,z\n0.1,0.2,0.3,0.01\n", 2, "row wider than the header");
  expect_text_error("0.1,0.2,0.3,-0.01\n", 1, "negative diameter");
  expect_text_error("0.1,0.2,0.3,0.01\n0.1,0.2,0.3,0\n", 2, "zero diameter");
  expect_text_error("0.1,0.2,0.3\nx,y,z\n", 2, "header after data");
  expect_text_error("x,y,z\nx,y,z\n", 2, "two headers");
  expect_text_error("x,y\n", 1, "two-column header");
  expect_text_error("x,1,z\n", 1, "half-numeric header");
}

TEST(SceneIo, MissingFileThrowsNamingIt) {
  TempDir dir;
  const std::string path = dir.file("does-not-exist.csv");
  for (int reader = 0; reader < 3; ++reader) {
    try {
      if (reader == 0) read_scene(path, Box{});
      if (reader == 1) read_text_scene(path, Box{});
      if (reader == 2) read_binary_scene(path);
      ADD_FAILURE() << "reader " << reader << " accepted a missing file";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    }
  }
}

void expect_binary_error(const std::string& path, const std::string& what) {
  for (int reader = 0; reader < 2; ++reader) {
    try {
      if (reader == 0) {
        read_scene(path, Box{});
      } else {
        read_binary_scene(path);
      }
      ADD_FAILURE() << what << ": accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << what << ": " << e.what();
    }
  }
}

TEST(SceneIo, BadBinaryFilesThrow) {
  TempDir dir;
  Scene scene = generated(SceneKind::kPolydisperse, 100, 3);
  const std::string good = dir.file("good.bin");
  write_binary_scene(scene, good);
  const std::string bytes = read_text(good);
  ASSERT_EQ(bytes.size(), 72u + 4 * 8 * 100);

  auto variant = [&](const std::string& name, const std::string& content) {
    std::string path = dir.file(name);
    write_text(path, content);
    return path;
  };
  // Truncated anywhere: in the arrays, at the end of the header, inside the header.
  expect_binary_error(variant("t1.bin", bytes.substr(0, bytes.size() - 8)),
                      "truncated by one double");
  expect_binary_error(variant("t2.bin", bytes.substr(0, bytes.size() - 1)),
                      "truncated by one byte");
  expect_binary_error(variant("t3.bin", bytes.substr(0, 72)), "header only");
  expect_binary_error(variant("t4.bin", bytes.substr(0, 40)), "cut inside the header");
  // Trailing bytes.
  expect_binary_error(variant("long.bin", bytes + std::string(8, '\0')), "extra bytes");
  // Wrong version, unknown flags.
  {
    std::string b = bytes;
    b[8] = 2;
    expect_binary_error(variant("version.bin", b), "version 2");
  }
  {
    std::string b = bytes;
    b[12] = 3;
    expect_binary_error(variant("flags.bin", b), "flags 3");
  }
  // Flag cleared: the size no longer matches 3 arrays.
  {
    std::string b = bytes;
    b[12] = 0;
    expect_binary_error(variant("noflag.bin", b), "diameter flag cleared");
  }
  // Huge N in the header (must not allocate or overflow).
  {
    std::string b = bytes;
    const std::uint64_t n = 0x2000000000000001ULL;
    std::memcpy(b.data() + 16, &n, 8);
    expect_binary_error(variant("hugen.bin", b), "huge N");
  }
  // Valid layout, invalid content: NaN coordinate, point outside its own box, zero diameter.
  {
    Scene s = scene;
    s.x[5] = std::numeric_limits<double>::quiet_NaN();
    std::string b = bytes;
    std::memcpy(b.data() + 72 + 5 * sizeof(double), &s.x[5], 8);
    expect_binary_error(variant("nan.bin", b), "NaN in binary");
  }
  {
    const double outside = 1.5;
    std::string b = bytes;
    std::memcpy(b.data() + 72 + (100 + 7) * sizeof(double), &outside, 8);  // y[7]
    expect_binary_error(variant("outside.bin", b), "outside in binary");
  }
  {
    const double zero = 0.0;
    std::string b = bytes;
    std::memcpy(b.data() + 72 + sizeof(double) * 3 * 100, &zero, 8);  // d[0]
    expect_binary_error(variant("zero-d.bin", b), "zero diameter in binary");
  }
  // read_binary_scene on a text file (read_scene would read it as text).
  EXPECT_THROW(read_binary_scene(variant("text.bin", "0.1,0.2,0.3\n")), InputError);
  EXPECT_EQ(read_scene(dir.file("text.bin"), Box{}).size(), 1u);
  EXPECT_THROW(read_binary_scene(variant("empty.bin", "")), InputError);
}

TEST(SceneIo, WritersReplaceFilesAtomically) {
  TempDir dir;
  const std::string path = dir.file("s.bin");
  write_text(path, "old content");
  const Scene scene = generated(SceneKind::kUniform, 10, 1);
  write_binary_scene(scene, path);
  expect_same_scene(read_scene(path, Box{}), scene);
  write_text_scene(scene, path);
  expect_same_scene(read_scene(path, Box{}), scene);
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"s.bin"});
  // Missing folders are made (as mkdir -p); under a file they cannot be, and nothing changes.
  write_binary_scene(scene, dir.file("missing/dir/s.bin"));
  expect_same_scene(read_scene(dir.file("missing/dir/s.bin"), Box{}), scene);
  write_text_scene(scene, dir.file("missing/dir/s.csv"));
  expect_same_scene(read_scene(dir.file("missing/dir/s.csv"), Box{}), scene);
  const std::string kept = read_text(path);
  EXPECT_THROW(write_binary_scene(scene, path + "/s.bin"), InputError);
  EXPECT_THROW(write_text_scene(scene, path + "/sub/s.csv"), InputError);
  EXPECT_EQ(read_text(path), kept);
  EXPECT_EQ(dir.entries(), (std::vector<std::string>{"missing", "s.bin"}));
}

}  // namespace
}  // namespace contactlab::test
