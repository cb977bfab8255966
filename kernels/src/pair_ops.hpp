// The pair ops of the detector's traversals (private to kernels/src): the contact test per
// candidate (ContactTest) or per home's slot ranges on SIMD lanes (SimdContactTest), the
// neighbour-list test (NeighborTest), the op that appends partners (ContactOp) and the op that
// only counts work (WorkCountOp). See traverse.hpp for the op protocol.
#pragma once

#include <cstdint>
#include <type_traits>
#include <vector>

#include "contactlab/kernels/detector.hpp"
#include "contactlab/kernels/pair_test.hpp"
#include "contactlab/kernels/slot_range.hpp"
#include "contactlab/kernels/traverse.hpp"
#include "src/simd_pair_tests.hpp"

namespace contactlab::pair_ops {

using traversal::Home;

// The contact test of pair_test.hpp, for one home at a time. In float, the pairs within the
// rounding band are tested again in double: the same contacts as the double test.
template <class Real, bool kDiameters>
struct ContactTest {
  const Real* d;
  Real reach_sq;             // D^2, without per-particle diameters
  ExactCoordinates exact{};  // float only
  FloatBand band{};          // float only

  struct ForHome {
    Real di;
    const Real* d;
    Real reach_sq;
    const ContactTest* test;
    std::uint32_t h;
    bool operator()(std::uint32_t j, Real dx, Real dy, Real dz) const {
      if constexpr (std::is_same_v<Real, float>) {
        bool unsure = false;
        bool hit = float_contact<kDiameters>(dx * dx + dy * dy + dz * dz,
                                             kDiameters ? di + d[j] : 0.0f, test->band, unsure);
        if (unsure) [[unlikely]]
          hit = test->exact.in_contact(h, j, kDiameters);
        return hit;
      } else if constexpr (kDiameters) {
        return in_contact(dx, dy, dz, di, d[j]);
      } else {
        return in_contact(dx, dy, dz, reach_sq);
      }
    }
  };
  ForHome for_home(std::uint32_t h) const {
    return {kDiameters ? d[h] : Real(0), d, reach_sq, this, h};
  }
};

// Below this many candidates a home (or, estimated from the cell occupancy, the average home
// of a scene) is tested in the scalar loop: a dispatched call and a masked vector per
// near-empty range cost more than 3-4 tests (the uniform scene at D = 1/200 ran 10-17 %
// slower at one thread on SIMD lanes).
inline constexpr std::uint64_t kSimdFrom = 16;

// The contact test of pair_test.hpp for a home's candidate slot ranges at once, on SIMD lanes
// (simd_pair_tests.hpp): sorted layouts only, where slots are working ids.
template <class Real, bool kDiameters>
struct SimdContactTest {
  const Real *x, *y, *z, *d;
  Real reach_sq;           // D^2, without per-particle diameters
  ExactCoordinates exact;  // float only
  FloatBand band;          // float only

  // Homes with fewer candidates than this are tested in the scalar loop (see kSimdFrom), unless
  // a target was named (simd_forced(): tests, benchmarks of a target).
  std::uint64_t scalar_below;

  struct ForHome {
    simd::RangeTask<Real> task;
    std::uint64_t candidates, scalar_below;
    std::size_t append(const SlotRange* ranges, int count, std::uint32_t* out) {
      if (candidates < scalar_below) {  // ContactTest's decision: the same contacts, bit for bit
        const ContactTest<Real, kDiameters> scalar{task.d, task.reach_sq, *task.exact, task.band};
        const auto test = scalar.for_home(task.home);
        std::size_t found = 0;
        for (int r = 0; r < count; ++r) {
          for (std::uint32_t j = ranges[r].begin; j < ranges[r].end; ++j) {
            out[found] = j;
            found += test(j, task.xi - task.x[j], task.yi - task.y[j], task.zi - task.z[j]);
          }
        }
        return found;
      }
      task.ranges = ranges;
      task.count = count;
      return simd::append_contacts(task, kDiameters, out);
    }
  };
  ForHome for_home(std::uint32_t h, std::uint64_t candidates) const {
    return {{x, y, z, d, x[h], y[h], z[h], kDiameters ? d[h] : Real(0), reach_sq, nullptr, 0, h,
             &exact, band},
            candidates,
            scalar_below};
  }
};

// The neighbour-list test: the contact test with every diameter (or D) widened by the skin,
// keeping each pair once (see ContactDetector::neighbor_list).
template <class Layout, bool kDiameters>
struct NeighborTest {
  using Real = typename Layout::Real;
  const Layout* layout;
  Real reach_sq;  // (D + skin)^2, without per-particle diameters
  Real skin;
  HomeRange homes;

  struct ForHome {
    Real di;  // d_i + skin
    const Layout* layout;
    Real reach_sq, skin;
    HomeRange homes;
    std::uint32_t input;  // the home's input row
    bool operator()(std::uint32_t j, Real dx, Real dy, Real dz) const {
      const std::uint32_t other = layout->input_of(j);
      // `&`, not `&&`: no branch in the hot loop.
      const bool once = other > input || !homes.contains(other);
      if constexpr (kDiameters) {
        return once & in_contact(dx, dy, dz, di, layout->d[j] + skin);
      } else {
        return once & in_contact(dx, dy, dz, reach_sq);
      }
    }
  };
  ForHome for_home(std::uint32_t h) const {
    return {kDiameters ? layout->d[h] + skin : Real(0),
            layout,
            reach_sq,
            skin,
            homes,
            layout->input_of(h)};
  }
};

// Appends each home's partners (those passing PairTest) to its thread's buffer, branchless,
// and records the home and its count for assemble_rows.
template <class PairTest>
class ContactOp {
 public:
  static constexpr bool kTestsPairs = true;

  ContactOp(const PairTest& test, detail::PartnerBuffer& out, LargeVector<std::uint32_t>& homes,
            std::uint32_t* found_count)
      : test_(test), out_(out), homes_(homes), found_count_(found_count) {}

  struct Sink {
    std::uint32_t* next;
    std::size_t found;
    typename PairTest::ForHome test;
    template <class Real>
    void operator()(std::uint32_t j, Real dx, Real dy, Real dz) {
      next[found] = j;
      found += test(j, dx, dy, dz);
    }
    // Tests that take whole slot ranges (SimdContactTest) are called once per home.
    void ranges(const SlotRange* r, int count) requires
        requires(typename PairTest::ForHome t, const SlotRange* q, std::uint32_t* o) {
      t.append(q, 0, o);
    }
    { found += test.append(r, count, next + found); }
  };
  Sink begin_home(const Home& home) {
    // The slack: the SIMD test stores whole vectors past its last find.
    return {out_.tail(home.tests + simd::kAppendSlack), 0, for_home(home)};
  }
  void end_home(const Home& home, const Sink& sink) {
    out_.advance(sink.found);
    found_count_[home.particle] = static_cast<std::uint32_t>(sink.found);
    homes_.push_back(home.particle);
    tests_ += home.tests;
  }
  std::uint64_t tests() const { return tests_; }

 private:
  auto for_home(const Home& home) const {
    if constexpr (requires { test_.for_home(home.particle, home.tests); }) {
      return test_.for_home(home.particle, home.tests);
    } else {
      return test_.for_home(home.particle);
    }
  }

  PairTest test_;
  detail::PartnerBuffer& out_;
  LargeVector<std::uint32_t>& homes_;
  std::uint32_t* found_count_;
  std::uint64_t tests_ = 0;
};

// Adds each home's tests, the home itself and its range builds to its loop iteration, without
// reading a candidate.
struct WorkCountOp {
  static constexpr bool kTestsPairs = false;
  LoopWork& work;

  struct Sink {};
  Sink begin_home(const Home&) { return {}; }
  void end_home(const Home& home, Sink) {
    work.tests[home.iteration] += static_cast<std::uint32_t>(home.tests);
    work.homes[home.iteration] += 1;
    if (home.built) work.builds[home.iteration] = 1;
  }
};

}  // namespace contactlab::pair_ops
