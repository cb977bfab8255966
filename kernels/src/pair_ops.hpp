// The pair ops of the detector's traversals (private to kernels/src): the contact test per
// candidate (ContactTest) or per block of a cell's homes on SIMD lanes (SimdContactTest), the
// neighbour-list test (NeighborTest), the op that appends partners (ContactOp) and the op that
// only counts work (WorkCountOp). See traverse.hpp for the op protocol.
#pragma once

#include <array>
#include <cstdint>
#include <cstring>
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
// of a scene) is tested in the scalar loop. With the homes of a cell in blocks, a vector call is
// shared by up to four: 4 (was 16 with one home a call) ran the paper scene's full stencil 3 %
// faster and its float variant 8 %; 0 (every home on lanes) ran the uniform scene's cell loop
// (about 3.5 candidates a home) 16 % slower (docs/architecture.md).
inline constexpr std::uint64_t kSimdFrom = 4;

// The contact test of pair_test.hpp for the homes of one cell at once, against their stencil's
// slot ranges, on SIMD lanes (simd_pair_tests.hpp): sorted layouts only, where slots are working
// ids.
template <class Real, bool kDiameters>
struct SimdContactTest {
  const Real *x, *y, *z, *d;
  Real reach_sq;           // D^2, without per-particle diameters
  ExactCoordinates exact;  // float only
  FloatBand band;          // float only

  // Homes with fewer candidates than this are tested in the scalar loop (see kSimdFrom), unless
  // a target was named (simd_forced(): tests, benchmarks of a target).
  std::uint64_t scalar_below;

  // Writes home b's partners to out[b] and their count to found[b] (homes: one cell's, in slot
  // order; each out[b] has room for the home's tests + kAppendSlack).
  void append_block(const Home* homes, int count, const traversal::NeighbourRanges& nb, bool half,
                    std::uint32_t* const* out, std::size_t* found) const {
    if (homes[0].tests < scalar_below) {  // ContactTest's decision: the same contacts, bit for bit
      const ContactTest<Real, kDiameters> scalar{d, reach_sq, exact, band};
      const traversal::SortedLayout<Real> layout{{nullptr, nullptr, nullptr, x, y, z, d}, nullptr};
      for (int b = 0; b < count; ++b) {
        const std::uint32_t h = homes[b].particle;
        // The count in a local: through found[b], each append waited for the last one's store.
        std::size_t hits = 0;
        auto append = [&hits, next = out[b], test = scalar.for_home(h)](std::uint32_t j, Real dx,
                                                                        Real dy, Real dz) {
          next[hits] = j;
          hits += test(j, dx, dy, dz);
        };
        if (half) {
          traversal::for_each_candidate<true>(layout, nb, h, h, append);
        } else {
          traversal::for_each_candidate<false>(layout, nb, h, h, append);
        }
        found[b] = hits;
      }
      return;
    }
    std::uint32_t slots[simd::kBlockHomes];
    for (int b = 0; b < count; ++b) slots[b] = homes[b].particle;
    const simd::BlockTask<Real> task{x,        y,      z,    d,     reach_sq, nb.ranges.data(),
                                     nb.count, nb.own, half, slots, count,    out,
                                     found,    &exact, band};
    simd::append_contacts(task, kDiameters);
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
// and records the home (appended to `out.homes`; homes_done() sets its size) and its count for
// assemble_rows.
template <class PairTest>
class ContactOp {
 public:
  static constexpr bool kTestsPairs = true;

  ContactOp(const PairTest& test, detail::ThreadOutput& out, std::uint32_t* found_count)
      : test_(test),
        out_(out.partners),
        home_list_(out.homes),
        block_rows_(out.block_rows),
        found_count_(found_count) {
    home_list_.clear();
    homes_ = home_list_.tail(std::max<std::size_t>(home_list_.capacity(), 4096));
    home_room_ = home_list_.capacity();
  }
  void homes_done() {
    home_list_.clear();
    home_list_.advance(visited_);
  }

  struct Sink {
    std::uint32_t* next;
    std::size_t found;
    typename PairTest::ForHome test;
    template <class Real>
    void operator()(std::uint32_t j, Real dx, Real dy, Real dz) {
      next[found] = j;
      found += test(j, dx, dy, dz);
    }
  };
  Sink begin_home(const Home& home) {
    return {out_.tail(home.tests), 0, test_.for_home(home.particle)};
  }
  void end_home(const Home& home, const Sink& sink) { record(home, sink.found); }

  // Tests that take the homes of a cell together (SimdContactTest) are called once per block.
  static constexpr int kBlockHomes =
      requires(const PairTest& t, const Home* h, std::uint32_t* const* o, std::size_t* f) {
    t.append_block(h, 1, traversal::NeighbourRanges{}, false, o, f);
  }
  ? simd::kBlockHomes : 1;
  // The first home's row is written in place; the others' go to the thread's block rows and
  // are moved behind it.
  void visit_block(const Home* homes, int count, const traversal::NeighbourRanges& nb,
                   bool half) requires(kBlockHomes > 1) {
    std::uint64_t tests = 0, spilled = 0;
    for (int b = 0; b < count; ++b) tests += homes[b].tests;
    std::uint32_t* const row = out_.tail(tests + simd::kAppendSlack);
    std::array<std::uint32_t*, simd::kBlockHomes> out{row};
    for (int b = 1; b < count; ++b) spilled += homes[b].tests + simd::kAppendSlack;
    if (block_rows_.size() < spilled) block_rows_.resize(spilled);
    std::uint32_t* spill = block_rows_.data();
    for (int b = 1; b < count; ++b) {
      out[b] = spill;
      spill += homes[b].tests + simd::kAppendSlack;
    }
    std::array<std::size_t, simd::kBlockHomes> found{};
    test_.append_block(homes, count, nb, half, out.data(), found.data());
    std::size_t at = found[0];
    for (int b = 1; b < count; ++b) {
      move_behind(row + at, out[b], found[b]);
      at += found[b];
    }
    for (int b = 0; b < count; ++b) record(homes[b], found[b]);
  }
  std::uint64_t tests() const { return tests_; }

 private:
  // Copies a block home's row behind the ones before it. Rows of up to kShortRow partners (a
  // sparse tile's home finds none to three) are one copy of fixed size, inlined: a call to
  // memcpy per such row cost more than the copy. Both sides have kAppendSlack entries of room
  // past the row (the spilled rows each, the block's first row behind all of them).
  static constexpr std::size_t kShortRow = 16;
  static_assert(kShortRow <= simd::kAppendSlack);
  static void move_behind(std::uint32_t* to, const std::uint32_t* from, std::size_t count) {
    if (count <= kShortRow) {
      std::memcpy(to, from, kShortRow * sizeof(std::uint32_t));
    } else {
      std::memcpy(to, from, count * sizeof(std::uint32_t));
    }
  }

  void record(const Home& home, std::size_t found) {
    out_.advance(found);
    found_count_[home.particle] = static_cast<std::uint32_t>(found);
    // A compare per home; the growth is out of line (a possible call in the hot path had made
    // the half stencil's one-thread loop a fifth slower on a 16-core Xeon).
    if (visited_ == home_room_) [[unlikely]]
      more_homes();
    homes_[visited_++] = home.particle;
    tests_ += home.tests;
  }

  PairTest test_;
  detail::PartnerBuffer& out_;
  [[gnu::noinline, gnu::cold]] void more_homes() {
    home_list_.clear();
    home_list_.advance(visited_);
    homes_ = home_list_.tail(visited_) - visited_;
    home_room_ = home_list_.capacity();
  }

  detail::PartnerBuffer& home_list_;
  std::uint32_t* homes_ = nullptr;
  std::size_t visited_ = 0, home_room_ = 0;
  LargeVector<std::uint32_t>& block_rows_;
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
