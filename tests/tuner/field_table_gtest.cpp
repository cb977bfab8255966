// Field tables (field_table.hpp): one table per record writes it and reads it back strictly,
// with nested records, vectors, optionals, maps, enums by name, computed fields, nested groups,
// fields older files lack, per-field checks and cross-field validation.
#include <gtest/gtest.h>

#include "contactlab/kernels/error.hpp"
#include "contactlab/tuner/field_table.hpp"

namespace contactlab::tuner {
namespace {

using nlohmann::json;

enum class Shape { kRound, kSquare };
std::string_view to_string(Shape s) { return s == Shape::kRound ? "round" : "square"; }
Shape parse_shape(std::string_view text) {
  if (text == "round") return Shape::kRound;
  if (text == "square") return Shape::kSquare;
  throw InputError("unknown shape '" + std::string(text) + "'");
}

struct Part {
  std::string name_;
  std::uint64_t count_ = 0;
};

struct Box {
  int version_ = 1;
  Shape shape_ = Shape::kRound;
  std::vector<Part> parts_;
  std::optional<double> weight_;
  std::map<std::string, std::uint64_t> tags_;
  int width_ = 0, depth_ = 0;
  std::string note_;  // newer than version 1 files
  int area() const { return width_ * depth_; }
};

void check_version(const JsonIn& at, const int& version) {
  if (version != 1) at.fail("unsupported version " + std::to_string(version));
}

}  // namespace

template <>
struct FieldTable<Part> {
  static constexpr auto kFields =
      std::tuple{field("name", &Part::name_), field("count", &Part::count_)};
  static void validate(const JsonIn& in, const Part& p) {
    if (p.name_.empty()) in.fail("a part needs a name");
  }
};

template <>
struct FieldTable<Box> {
  static constexpr auto kFields =
      std::tuple{field("version", &Box::version_).checked(&check_version),
                 field("shape", &Box::shape_).via(EnumCodec<&parse_shape>{}),
                 field("parts", &Box::parts_),
                 field("weight", &Box::weight_),
                 field("tags", &Box::tags_),
                 group("size", field("width", &Box::width_), field("depth", &Box::depth_)),
                 computed("area", &Box::area, "width * depth"),
                 field("note", &Box::note_).may_be_absent()};
};

namespace {

Box sample_box() {
  Box b;
  b.shape_ = Shape::kSquare;
  b.parts_ = {{"lid", 1}, {"wall", 4}};
  b.tags_ = {{"fragile", 1}};
  b.width_ = 3;
  b.depth_ = 2;
  b.note_ = "keep dry";
  return b;
}

std::string rejection(const json& j) {
  try {
    Box b;
    read(JsonIn(j, "$"), b);
  } catch (const SchemaError& e) {
    return e.what();
  }
  return "";
}

TEST(FieldTable, WritesEveryFieldOnce) {
  const json j = to_json_value(sample_box());
  EXPECT_EQ(j, json::parse(R"({"version": 1, "shape": "square", "weight": null,
      "parts": [{"name": "lid", "count": 1}, {"name": "wall", "count": 4}],
      "tags": {"fragile": 1}, "size": {"width": 3, "depth": 2}, "area": 6,
      "note": "keep dry"})"));
}

TEST(FieldTable, ReadsBackWhatItWrote) {
  const json j = to_json_value(sample_box());
  Box b;
  read(JsonIn(j, "$"), b);
  EXPECT_EQ(to_json_value(b), j);
  EXPECT_EQ(b.shape_, Shape::kSquare);
  EXPECT_EQ(b.parts_[1].count_, 4u);
}

TEST(FieldTable, ReadsStrictlyWithThePath) {
  const json good = to_json_value(sample_box());
  json j = good;
  j["parts"][1]["colour"] = "red";
  EXPECT_EQ(rejection(j), "$.parts[1]: unknown field 'colour'");
  j = good;
  j["size"].erase("depth");
  EXPECT_EQ(rejection(j), "$.size: missing field 'depth'");
  j = good;
  j["tags"]["fragile"] = "yes";
  EXPECT_EQ(rejection(j), "$.tags.fragile: expected non-negative integer, got \"yes\"");
  j = good;
  j["shape"] = "oval";
  EXPECT_EQ(rejection(j), "$: shape: unknown shape 'oval'");
  j = good;
  j["version"] = 2;
  j["colour"] = "red";  // the version is checked first
  EXPECT_EQ(rejection(j), "$.version: unsupported version 2");
  j = good;
  j["area"] = 7;
  EXPECT_EQ(rejection(j), "$: area = 7 does not match width * depth = 6");
  j = good;
  j["parts"][0]["name"] = "";
  EXPECT_EQ(rejection(j), "$.parts[0]: a part needs a name");
}

TEST(FieldTable, FieldsOlderFilesLackMayBeAbsent) {
  json j = to_json_value(sample_box());
  j.erase("note");
  Box b;
  b.note_ = "stale";
  read(JsonIn(j, "$"), b);
  EXPECT_EQ(b.note_, "");  // the record's default, not what was there before
  j.erase("weight");
  EXPECT_EQ(rejection(j), "$: missing field 'weight'");
}

}  // namespace
}  // namespace contactlab::tuner
