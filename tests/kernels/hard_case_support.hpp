// What the hard-case suites share (hard_cases_gtest.cpp, hard_cases_rounding_gtest.cpp): each
// case states its expected contacts, then expect_variants_match runs the variants against them.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <utility>
#include <vector>

#include "contactlab/kernels/simd.hpp"
#include "test_support.hpp"

namespace contactlab::test {

using Pairs = std::vector<std::pair<std::uint32_t, std::uint32_t>>;

// Runs `variants` x `threads` and compares each canonical result with `expected` (float
// variants too: their pairs within rounding of touching are decided in double); stops
// reporting after a few failures so that one bug does not bury the output.
inline void expect_variants_match(const Scene& scene, double d, const ContactList& expected,
                                  const std::vector<Variant>& variants,
                                  const std::vector<int>& threads = {1, 2, 3}) {
  int failures = 0;
  for (const Variant& variant : variants) {
    // The sorted layouts test on SIMD lanes: every target this CPU runs, and the scalar loop.
    const std::vector<std::string> targets =
        variant.order == Order::kUnsorted ? std::vector<std::string>{"best"} : simd_targets();
    for (const std::string& target : targets) {
      select_simd_target(target);
      // On the best target in double, also every thread count users run up to 16 (the rows
      // assembled by many threads, the registration's wider top digit), oversubscribed here.
      std::vector<int> counts = threads;
      if (target == targets.front() && variant.precision == Precision::kDouble) {
        for (const int more : {4, 8, 16}) {
          if (std::find(counts.begin(), counts.end(), more) == counts.end()) counts.push_back(more);
        }
      }
      for (const int t : counts) {
        const Detected got = detect(scene, variant, d, t);
        const auto same = same_contacts(got.contacts, expected);
        if (!same || got.run.contact_pairs != expected.pair_count()) {
          ADD_FAILURE() << to_string(variant) << " simd=" << target << " threads=" << t << ": "
                        << same.message() << " (contact_pairs " << got.run.contact_pairs << ")";
          if (++failures >= 5) break;
        }
      }
      if (failures >= 5) break;
    }
    select_simd_target("best");
    if (failures >= 5) return;
  }
}

}  // namespace contactlab::test
