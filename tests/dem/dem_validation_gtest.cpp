// Each DEM validation case (the rows `contactlab dem validate` prints) as a test: every row
// must pass.
#include <gtest/gtest.h>

#include "contactlab/dem/validation.hpp"

namespace contactlab::dem {
namespace {

class DemValidation : public ::testing::TestWithParam<std::string> {};

TEST_P(DemValidation, EveryRowPasses) {
  for (const ValidationCase& c : validation_cases()) {
    if (c.name != GetParam()) continue;
    const std::vector<ValidationRow> rows = c.run();
    ASSERT_FALSE(rows.empty());
    for (const ValidationRow& r : rows) {
      EXPECT_TRUE(r.pass) << r.case_name << ": " << r.quantity << " expected " << r.expected
                          << " measured " << r.measured << " error " << r.error << " > "
                          << r.tolerance << " (" << r.note << ")";
    }
    return;
  }
  FAIL() << "no case " << GetParam();
}

INSTANTIATE_TEST_SUITE_P(Cases, DemValidation,
                         ::testing::Values("normal-impact", "elastic-gas", "momentum",
                                           "resting-column", "oblique-impact", "slide-to-roll",
                                           "rolling-resistance", "stability"),
                         [](const auto& param_info) {
                           std::string name = param_info.param;
                           for (char& ch : name) ch = ch == '-' ? '_' : ch;
                           return name;
                         });

TEST(DemValidationCases, AllAreRegistered) { EXPECT_EQ(validation_cases().size(), 8u); }

}  // namespace
}  // namespace contactlab::dem
