// Variant strings: canonical printing, parsing, round trips, defaults and rejected input.
#include <gtest/gtest.h>

#include <set>

#include "contactlab/kernels/error.hpp"
#include "test_support.hpp"

namespace contactlab::test {
namespace {

TEST(Variant, EnumerationCoversTheWholeSpace) {
  const VariantSpace space = all_variants({1, 7, 64});
  EXPECT_EQ(space.loops.size(), 2u);
  EXPECT_EQ(space.orders.size(), 3u);
  EXPECT_EQ(space.stencils.size(), 2u);
  EXPECT_EQ(space.precisions, (std::vector<Precision>{Precision::kDouble, Precision::kFloat}));
  // Both indexes, explicitly (auto is one of them on every scene).
  EXPECT_EQ(space.grids, (std::vector<GridIndex>{GridIndex::kDense, GridIndex::kHashed}));
  // static, balanced, then static,k dynamic,k guided,k for each k.
  ASSERT_EQ(space.schedules.size(), 11u);
  EXPECT_EQ(space.schedules[0], (Schedule{ScheduleKind::kStatic, 0}));
  std::set<std::string> schedules;
  for (const auto& s : space.schedules) schedules.insert(to_string(s));
  EXPECT_EQ(schedules, (std::set<std::string>{"static", "balanced", "static,1", "static,7",
                                              "static,64", "dynamic,1", "dynamic,7", "dynamic,64",
                                              "guided,1", "guided,7", "guided,64"}));
  const auto variants = enumerate(space);
  ASSERT_EQ(variants.size(), 2u * 3u * 2u * 11u * 2u * 2u);
  std::set<std::string> names;
  for (const auto& v : variants) names.insert(to_string(v));
  EXPECT_EQ(names.size(), variants.size()) << "duplicates in the enumeration";
  EXPECT_TRUE(enumerate(VariantSpace{}).empty());
  EXPECT_EQ(enumerate(all_variants({})).size(), 96u);  // only plain static and balanced
  // A space left at its default precision and grid enumerates double, auto variants only.
  VariantSpace doubles = space;
  doubles.precisions = VariantSpace{}.precisions;
  doubles.grids = VariantSpace{}.grids;
  EXPECT_EQ(doubles.precisions, std::vector<Precision>{Precision::kDouble});
  EXPECT_EQ(doubles.grids, std::vector<GridIndex>{GridIndex::kAuto});
  EXPECT_EQ(enumerate(doubles).size(), 132u);
}

TEST(Variant, RoundTripForEveryEnumeratedVariant) {
  for (const Variant& v : every_variant()) {
    const std::string text = to_string(v);
    EXPECT_EQ(parse_variant(text), v) << text;
    EXPECT_EQ(to_string(parse_variant(text)), text);
    // Canonical form: four parts, a fifth only for float, then the grid unless auto.
    const long parts = std::count(text.begin(), text.end(), '/') + 1;
    EXPECT_EQ(parts, (v.precision == Precision::kFloat ? 5 : 4) + (v.grid != GridIndex::kAuto))
        << text;
  }
}

TEST(Variant, CanonicalText) {
  EXPECT_EQ(to_string(Variant{
                LoopKind::kParticle, Order::kSorted, Stencil::kFull, {ScheduleKind::kStatic, 200}}),
            "particle/sorted/full/static,200");
  EXPECT_EQ(to_string(Variant{
                LoopKind::kCell, Order::kMorton, Stencil::kHalf, {ScheduleKind::kGuided, 4}}),
            "cell/morton/half/guided,4");
  EXPECT_EQ(to_string(Variant{LoopKind::kCell, Order::kUnsorted, Stencil::kFull, {}}),
            "cell/unsorted/full/static");
  EXPECT_EQ(to_string(Variant{LoopKind::kCell,
                              Order::kSorted,
                              Stencil::kHalf,
                              {ScheduleKind::kDynamic, 7},
                              Precision::kFloat}),
            "cell/sorted/half/dynamic,7/float");
  EXPECT_EQ(to_string(Schedule{ScheduleKind::kStatic, 0}), "static");
  EXPECT_EQ(to_string(Schedule{ScheduleKind::kStatic, 200}), "static,200");
  EXPECT_EQ(to_string(Schedule{ScheduleKind::kDynamic, 4}), "dynamic,4");
  EXPECT_EQ(to_string(LoopKind::kCell), "cell");
  EXPECT_EQ(to_string(LoopKind::kParticle), "particle");
  EXPECT_EQ(to_string(Order::kUnsorted), "unsorted");
  EXPECT_EQ(to_string(Order::kSorted), "sorted");
  EXPECT_EQ(to_string(Order::kMorton), "morton");
  EXPECT_EQ(to_string(Stencil::kFull), "full");
  EXPECT_EQ(to_string(Stencil::kHalf), "half");
  EXPECT_EQ(to_string(ScheduleKind::kGuided), "guided");
  EXPECT_EQ(to_string(Precision::kDouble), "double");
  EXPECT_EQ(to_string(Precision::kFloat), "float");
  // The default Variant is the paper's sorted particle loop with a block partition, in double.
  EXPECT_EQ(to_string(Variant{}), "particle/sorted/full/static");
  EXPECT_EQ(Variant{}.precision, Precision::kDouble);
}

TEST(Variant, PrecisionPart) {
  EXPECT_EQ(parse_variant("cell/sorted/half/dynamic,7/float").precision, Precision::kFloat);
  EXPECT_EQ(parse_variant("cell/sorted/half/dynamic,7/double"),
            parse_variant("cell/sorted/half/dynamic,7"));
  EXPECT_EQ(to_string(parse_variant("cell/sorted/half/dynamic,7/double")),
            "cell/sorted/half/dynamic,7");
  EXPECT_EQ(parse_variant("particle/morton/full/guided/float"), (Variant{LoopKind::kParticle,
                                                                         Order::kMorton,
                                                                         Stencil::kFull,
                                                                         {ScheduleKind::kGuided, 1},
                                                                         Precision::kFloat}));
  EXPECT_EQ(parse_precision("double"), Precision::kDouble);
  EXPECT_EQ(parse_precision("float"), Precision::kFloat);
  for (const char* text : {"", "single", "Float", "f32", "half"}) {
    EXPECT_THROW(parse_precision(text), InputError) << "'" << text << "'";
  }
}

TEST(Variant, GridPart) {
  EXPECT_EQ(Variant{}.grid, GridIndex::kAuto);
  EXPECT_EQ(parse_variant("cell/sorted/half/dynamic,7").grid, GridIndex::kAuto);
  EXPECT_EQ(parse_variant("cell/sorted/half/dynamic,7/grid=auto"),
            parse_variant("cell/sorted/half/dynamic,7"));
  const Variant hashed = parse_variant("cell/sorted/half/dynamic,7/float/grid=hashed");
  EXPECT_EQ(hashed.grid, GridIndex::kHashed);
  EXPECT_EQ(hashed.precision, Precision::kFloat);
  EXPECT_EQ(to_string(hashed), "cell/sorted/half/dynamic,7/float/grid=hashed");
  EXPECT_EQ(parse_variant("particle/morton/static/grid=dense").grid, GridIndex::kDense);
  EXPECT_EQ(to_string(parse_variant("particle/morton/static/grid=dense")),
            "particle/morton/full/static/grid=dense");
  EXPECT_EQ(parse_grid_index("hashed"), GridIndex::kHashed);
  EXPECT_EQ(to_string(GridIndex::kDense), "dense");
  for (const char* text : {"particle/sorted/static/grid=sparse", "particle/sorted/static/grid=",
                           "particle/sorted/static/grid=dense/grid=hashed"}) {
    EXPECT_THROW(parse_variant(text), InputError) << text;
  }
}

TEST(Variant, ThreePartFormMeansFullStencil) {
  EXPECT_EQ(parse_variant("particle/sorted/static,200"),
            parse_variant("particle/sorted/full/static,200"));
  EXPECT_EQ(parse_variant("cell/morton/dynamic,3").stencil, Stencil::kFull);
  EXPECT_EQ(to_string(parse_variant("cell/unsorted/guided,9")), "cell/unsorted/full/guided,9");
}

TEST(Variant, ScheduleDefaults) {
  EXPECT_EQ(parse_schedule("dynamic"), parse_schedule("dynamic,1"));
  EXPECT_EQ(parse_schedule("dynamic"), (Schedule{ScheduleKind::kDynamic, 1}));
  EXPECT_EQ(parse_schedule("guided"), (Schedule{ScheduleKind::kGuided, 1}));
  EXPECT_EQ(parse_schedule("static"), (Schedule{ScheduleKind::kStatic, 0}));
  EXPECT_EQ(parse_schedule("balanced"), (Schedule{ScheduleKind::kBalanced, 0}));
  EXPECT_EQ(to_string(Schedule{ScheduleKind::kBalanced, 0}), "balanced");
  EXPECT_THROW(parse_schedule("balanced,64"), InputError);
  EXPECT_FALSE(has_valid_chunk({ScheduleKind::kBalanced, 4}));
  EXPECT_TRUE(has_valid_chunk({ScheduleKind::kStatic, 0}));
  EXPECT_FALSE(has_valid_chunk({ScheduleKind::kDynamic, 0}));
  EXPECT_EQ(parse_schedule("static,1"), (Schedule{ScheduleKind::kStatic, 1}));
  EXPECT_EQ(parse_schedule("guided,1000000000"), (Schedule{ScheduleKind::kGuided, 1000000000}));
  EXPECT_EQ(parse_variant("particle/unsorted/half/dynamic").schedule,
            (Schedule{ScheduleKind::kDynamic, 1}));
}

TEST(Variant, ComponentParsers) {
  EXPECT_EQ(parse_loop("cell"), LoopKind::kCell);
  EXPECT_EQ(parse_loop("particle"), LoopKind::kParticle);
  EXPECT_EQ(parse_order("unsorted"), Order::kUnsorted);
  EXPECT_EQ(parse_order("sorted"), Order::kSorted);
  EXPECT_EQ(parse_order("morton"), Order::kMorton);
  EXPECT_EQ(parse_stencil("full"), Stencil::kFull);
  EXPECT_EQ(parse_stencil("half"), Stencil::kHalf);
}

// One-line message naming the bad part.
void expect_input_error(const std::string& text, const std::string& must_mention) {
  try {
    parse_variant(text);
    ADD_FAILURE() << "'" << text << "' was accepted";
  } catch (const InputError& e) {
    const std::string message = e.what();
    EXPECT_EQ(message.find('\n'), std::string::npos) << "multi-line message: " << message;
    EXPECT_NE(message.find(must_mention), std::string::npos)
        << "message for '" << text << "' does not mention '" << must_mention << "': " << message;
  }
}

TEST(Variant, BadStringsThrowInputError) {
  expect_input_error("loop/sorted/full/static", "loop");
  expect_input_error("cells/sorted/full/static", "cells");
  expect_input_error("particle/random/full/static", "random");
  expect_input_error("particle/sorted/quarter/static", "quarter");
  expect_input_error("particle/sorted/full/auto", "auto");
  expect_input_error("particle/sorted/full/static,0", "static,0");
  expect_input_error("particle/sorted/full/static,-3", "static,-3");
  expect_input_error("particle/sorted/full/static,abc", "abc");
  expect_input_error("particle/sorted/full/dynamic,", "dynamic,");
  expect_input_error("particle/sorted/full/dynamic,1,2", "dynamic,1,2");
  expect_input_error("particle/sorted/full/static,1.5", "1.5");
  expect_input_error("particle/sorted/full/static,99999999999", "99999999999");
  expect_input_error("particle/sorted", "particle/sorted");
  expect_input_error("particle", "particle");
  expect_input_error("", "");
  expect_input_error("particle/sorted/full/static/extra", "extra");
  expect_input_error("particle/sorted/full/static/float/extra",
                     "particle/sorted/full/static/float/extra");
  expect_input_error("particle/sorted/full/static,1/", "precision");
  expect_input_error("particle/sorted/full/static/single", "single");
  // The precision needs the four-part form: a fourth part is always the schedule.
  expect_input_error("particle/sorted/static,200/float", "static,200");
  expect_input_error("Particle/sorted/full/static", "Particle");
  expect_input_error("particle/sorted//static", "");
  // The choices are listed for an unknown name.
  expect_input_error("particle/random/full/static", "morton");
  expect_input_error("nope/sorted/full/static", "particle");
}

TEST(Variant, BadSchedulesThrowInputError) {
  for (const char* text : {"static,0", "static,-3", "static,abc", "dynamic,", "dynamic,,", ",4", "",
                           "Static", "static,+4", "static, 4", "static,4 ", "runtime"}) {
    EXPECT_THROW(parse_schedule(text), InputError) << "'" << text << "'";
  }
  for (const char* text : {"", "Cell", " cell"}) EXPECT_THROW(parse_loop(text), InputError) << text;
  for (const char* text : {"", "Sorted", "z-order"})
    EXPECT_THROW(parse_order(text), InputError) << text;
  for (const char* text : {"", "Full", "27"}) EXPECT_THROW(parse_stencil(text), InputError) << text;
}

// The axis table drives the text form: every axis and value appears in the help, every
// enumerated variant prints and parses through it, and named parts are read.
TEST(VariantAxes, TableDrivesHelpParsingAndPrinting) {
  const std::string help = variants_help();
  for (const VariantAxis& axis : variant_axes()) {
    EXPECT_NE(help.find(std::string(axis.name)), std::string::npos) << axis.name;
    for (const auto value : axis.values) {
      EXPECT_NE(help.find(std::string(value)), std::string::npos) << axis.name << " " << value;
    }
  }
  EXPECT_EQ(variant_axes().size(), 6u);
  EXPECT_EQ(parse_variant("particle/sorted/half/static,200/precision=float"),
            parse_variant("particle/sorted/half/static,200/float"));
  EXPECT_EQ(parse_variant("cell/morton/guided,4/precision=double"),
            parse_variant("cell/morton/full/guided,4"));
  expect_input_error("particle/sorted/full/static/colour=red", "unknown variant axis 'colour'");
  expect_input_error("particle/sorted/full/static/loop=cell", "axis 'loop' given twice");
  expect_input_error("particle/sorted/full/static/float/precision=double",
                     "axis 'precision' given twice");
  expect_input_error("particle/sorted/full/static/precision=quad", "unknown precision 'quad'");
}

TEST(VariantAxes, EveryEnumeratedVariantKeepsTheRules) {
  for (const Variant& v : every_variant()) {
    EXPECT_FALSE(broken_rule(v).has_value()) << to_string(v);
  }
  for (const VariantRule& rule : variant_rules()) {
    EXPECT_FALSE(rule.description.empty());
    EXPECT_NE(rule.holds, nullptr);
  }
}

TEST(Variant, PaperVariants) {
  const auto variants = paper_variants();
  std::vector<std::string> names;
  names.reserve(variants.size());
  for (const auto& v : variants) names.push_back(to_string(v));
  EXPECT_EQ(names,
            (std::vector<std::string>{"particle/unsorted/full/static", "cell/unsorted/full/static",
                                      "particle/sorted/full/static", "cell/sorted/full/static",
                                      "particle/sorted/full/static,200"}));
}

}  // namespace
}  // namespace contactlab::test
