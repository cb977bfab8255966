// The SIMD contact test (simd_pair_tests.hpp), compiled once per Highway target by
// foreach_target.h, and the process-wide choice of target (simd.hpp).
//
// Per vector of candidates: the distances of pair_test.hpp lane by lane (Mul, Add: no fused
// multiply-add, as -ffp-contract=off keeps the scalar test), the contact mask, and the slots
// that hit compressed to the front of a vector and stored whole (a compressing store to memory
// is microcoded on some AVX-512 CPUs); the count advances by the hits, as the scalar
// branchless append does.
#include "src/simd_pair_tests.hpp"

#ifndef CONTACTLAB_NO_SIMD
// Every target Highway attains (not only those above the build's baseline): with -march=native
// the AVX2, SSE4 and EMU128 paths are compiled too, so tests run each of them.
// AVX3_DL (AVX-512 with VBMI2, VNNI, ...) too: on such CPUs it is the native build's baseline.
#define HWY_COMPILE_ALL_ATTAINABLE
#define HWY_WANT_AVX3_DL
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "src/simd_pair_tests.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <type_traits>
#include <utility>

#ifndef CONTACTLAB_COMPRESS_TABLES  // once per translation unit, not once per target
#define CONTACTLAB_COMPRESS_TABLES
namespace contactlab::simd::detail {
// Where a vector has no compress instruction (AVX2, SSE4, SSSE3), the hits move to the front by
// a shuffle looked up by the hit mask. Highway 1.0's own Compress keeps its shuffle tables in
// local arrays that GCC copies to the stack at every vector (256 bytes with double lanes, 1 KiB
// with float): with them the AVX2 test ran no faster than the scalar loop.
// Row m: the lanes set in m in ascending order, then the others (lane indices of 8 lanes).
constexpr std::array<std::array<std::uint32_t, 8>, 256> compress_lanes() {
  std::array<std::array<std::uint32_t, 8>, 256> table{};
  for (std::uint32_t m = 0; m < 256; ++m) {
    std::uint32_t k = 0;
    for (std::uint32_t l = 0; l < 8; ++l) {
      if ((m >> l) & 1) table[m][k++] = l;
    }
    for (std::uint32_t l = 0; l < 8; ++l) {
      if (!((m >> l) & 1)) table[m][k++] = l;
    }
  }
  return table;
}
// The same for 4 lanes of 4 bytes as byte indices (128-bit and narrower vectors).
constexpr std::array<std::array<std::uint8_t, 16>, 16> compress_bytes() {
  std::array<std::array<std::uint8_t, 16>, 16> table{};
  const auto lanes = compress_lanes();
  for (std::uint32_t m = 0; m < 16; ++m) {
    for (std::uint32_t k = 0; k < 4; ++k) {
      for (std::uint32_t b = 0; b < 4; ++b) {
        table[m][4 * k + b] = static_cast<std::uint8_t>(4 * lanes[m][k] + b);
      }
    }
  }
  return table;
}
alignas(64) inline constexpr auto kCompressLanes = compress_lanes();
alignas(64) inline constexpr auto kCompressBytes = compress_bytes();
}  // namespace contactlab::simd::detail
#endif

// The lambdas of the test inlined into its loops (GCC outlined the per-home test of a range's
// last vector: a call per home and range).
#ifndef CONTACTLAB_INLINE
#define CONTACTLAB_INLINE __attribute__((always_inline))
#endif

HWY_BEFORE_NAMESPACE();
namespace contactlab::simd {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

// The first `count` lanes (those of `valid`) loaded from p, the others zero, reading nothing past
// p[count - 1]: a range's last vector may end at the array's end. AVX2 and AVX-512 load only the
// lanes. Below AVX2 Highway 1.0's MaskedLoad is an aligned load of the whole vector and a blend
// (it faulted at a range's unaligned last vector wherever GCC did not fold it into the next
// instruction), and an unaligned load of the whole vector reads past the array (AddressSanitizer
// reported it; where the array ends at an unmapped page it would fault): the lanes are copied
// to a zeroed vector on the stack instead, a scalar copy of at most three.
template <class D, class T>
HWY_INLINE hn::Vec<D> LoadFirst(D d, [[maybe_unused]] hn::Mask<D> valid, const T* HWY_RESTRICT p,
                                [[maybe_unused]] std::uint32_t count) {
#if HWY_TARGET <= HWY_AVX2
  return hn::MaskedLoad(valid, d, p);
#else
  alignas(16) T lanes[hn::MaxLanes(d)] = {};
  for (std::uint32_t l = 0; l < count; ++l) lanes[l] = p[l];
  return hn::Load(d, lanes);
#endif
}

template <int kHomes, bool kDiameters, class Real>
void AppendBlock(const BlockTask<Real>& task) {
  const hn::ScalableTag<Real> d;
  const hn::Rebind<std::uint32_t, decltype(d)> du;  // a slot per coordinate lane
  using V = hn::Vec<decltype(d)>;
  const std::size_t lanes = hn::Lanes(d);
  const auto reach_sq = hn::Set(d, task.reach_sq);
  const auto four = hn::Set(d, Real(4));
  [[maybe_unused]] const auto sure_sq = hn::Set(d, static_cast<Real>(task.band.sure));
  [[maybe_unused]] const auto unsure_sq = hn::Set(d, static_cast<Real>(task.band.unsure));
  [[maybe_unused]] const auto margin = hn::Set(d, static_cast<Real>(task.band.margin));
  [[maybe_unused]] const auto minus_margin = hn::Set(d, static_cast<Real>(-task.band.margin));
  // The slots of a vector are iota + s. Iota itself is not in the loop: Highway 1.0 builds it
  // lane by lane through the stack, and the vector load of those narrow stores cannot be
  // forwarded from them (a stall of every vector with AVX-512).
  const auto iota = hn::Iota(du, 0);
  // Targets without a compress instruction move the hits by a table (see kCompressLanes).
  constexpr bool kCompressByTable =
      (HWY_TARGET == HWY_AVX2 || HWY_TARGET == HWY_SSE4 || HWY_TARGET == HWY_SSSE3) &&
      hn::MaxLanes(du) >= 2 && hn::MaxLanes(du) <= 8;
  // The arrays in locals: through `task`, every store to an output would reload them (it may
  // alias).
  const Real* HWY_RESTRICT const px = task.x;
  const Real* HWY_RESTRICT const py = task.y;
  const Real* HWY_RESTRICT const pz = task.z;
  [[maybe_unused]] const Real* HWY_RESTRICT const pd = task.d;

  // A home as the lanes see it: its coordinates broadcast, and where its partners go.
  struct HomeLanes {
    V x, y, z, d;
    std::uint32_t slot;
    // The next partner's place. A cursor, not a base and a count: four homes' bases and counts,
    // the slots and the arrays outnumbered the general registers, and the counts, kept on the
    // stack, made every vector wait for a store and a reload.
    std::uint32_t* HWY_RESTRICT out;
  };
  // One home against a vector of candidates at slots s.. (c*: their coordinates) that `valid`
  // holds: a whole vector (kWhole) or a range's last one (the lanes before its end).
  // In the homes' own row every home is tested against the whole vector too, and `kOwnRow` drops
  // the slots it must not find: its own (full stencil) or those up to its own (half stencil).
  auto test_home = [&](HomeLanes& home, const std::uint32_t s, const std::uint32_t end, V cx, V cy,
                       V cz, V cd, const auto valid, const auto whole_tag,
                       const auto own_row_tag) CONTACTLAB_INLINE {
    constexpr bool kWhole = decltype(whole_tag)::value;
    constexpr bool kOwnRow = decltype(own_row_tag)::value;
    const auto slots = hn::Add(iota, hn::Set(du, s));
    // The slots the home may find, on the slots' lanes (used only in the own row).
    auto partner_slots = [&] {
      const auto own = hn::Set(du, home.slot);
      return task.half ? hn::Gt(slots, own) : hn::Ne(slots, own);
    };
    const auto dx = hn::Sub(home.x, cx);
    const auto dy = hn::Sub(home.y, cy);
    const auto dz = hn::Sub(home.z, cz);
    const auto dist_sq = hn::Add(hn::Add(hn::Mul(dx, dx), hn::Mul(dy, dy)), hn::Mul(dz, dz));
    auto hit = hn::Le(dist_sq, reach_sq);
    if constexpr (std::is_same_v<Real, float>) {  // the band of pair_test.hpp's float_contact
      auto maybe = hn::Le(dist_sq, unsure_sq);
      hit = hn::Le(dist_sq, sure_sq);
      if constexpr (kDiameters) {
        const auto sum = hn::Add(home.d, cd);
        const auto t = hn::Sub(hn::Mul(sum, sum), hn::Mul(four, dist_sq));
        hit = hn::Ge(t, margin);
        maybe = hn::Ge(t, minus_margin);
      }
      if constexpr (!kWhole) {
        hit = hn::And(hit, valid);
        maybe = hn::And(maybe, valid);
      }
      if constexpr (kOwnRow) {  // float and slot lanes are the same width
        const auto partner = hn::RebindMask(d, partner_slots());
        hit = hn::And(hit, partner);
        maybe = hn::And(maybe, partner);
      }
      const auto unsure = hn::AndNot(hit, maybe);
      if (!hn::AllFalse(d, unsure)) [[unlikely]] {  // lane by lane, the unsure ones in double
        std::uint8_t hit_bits[HWY_MAX_BYTES / 4 + 8] = {}, unsure_bits[HWY_MAX_BYTES / 4 + 8] = {};
        hn::StoreMaskBits(d, hit, hit_bits);
        hn::StoreMaskBits(d, unsure, unsure_bits);
        const std::uint32_t count =
            std::min<std::uint32_t>(static_cast<std::uint32_t>(lanes), end - s);
        for (std::uint32_t l = 0; l < count; ++l) {
          bool lane_hit = (hit_bits[l / 8] >> (l % 8)) & 1;
          if ((unsure_bits[l / 8] >> (l % 8)) & 1) {
            lane_hit = task.exact->in_contact(home.slot, s + l, kDiameters);
          }
          *home.out = s + l;
          home.out += lane_hit;
        }
        return;
      }
    } else if constexpr (kDiameters) {
      const auto sum = hn::Add(home.d, cd);
      hit = hn::Le(hn::Mul(four, dist_sq), hn::Mul(sum, sum));
    }
    if constexpr (!kWhole) hit = hn::And(hit, valid);
    std::uint32_t* HWY_RESTRICT const out = home.out;
    if constexpr (kCompressByTable) {  // at most 8 lanes: the mask is one byte
      std::uint8_t bits[8] = {};
      hn::StoreMaskBits(d, hit, bits);
      if constexpr (kOwnRow && !std::is_same_v<Real, float>) {  // float: dropped above
        std::uint8_t partner_bits[8] = {};
        hn::StoreMaskBits(du, partner_slots(), partner_bits);
        bits[0] &= partner_bits[0];
      }
      if constexpr (hn::MaxLanes(du) == 8) {
        const auto index = hn::LoadU(du, detail::kCompressLanes[bits[0]].data());
        hn::StoreU(hn::TableLookupLanes(slots, hn::IndicesFromVec(du, index)), du, out);
      } else {
        const hn::Repartition<std::uint8_t, decltype(du)> du8;
        const auto index = hn::LoadU(du8, detail::kCompressBytes[bits[0]].data());
        hn::StoreU(hn::TableLookupBytes(slots, hn::BitCast(du, index)), du, out);
      }
      home.out += std::popcount(bits[0]);
      return;
    }
    decltype(hn::FirstN(du, 0)) slot_hit;
    if constexpr (sizeof(Real) == sizeof(std::uint32_t)) {
      slot_hit = hn::RebindMask(du, hit);
#if HWY_TARGET <= HWY_AVX3
      // NOLINTNEXTLINE(readability-simplify-boolean-expr): a branch only AVX-512 targets have
    } else if constexpr (true) {  // AVX-512: both are the same 8-bit mask register
      slot_hit.raw = hit.raw;
#endif
    } else {  // double lanes: the mask by its bits onto the half-width slot vector
      std::uint8_t bits[HWY_MAX_BYTES / 8 + 8] = {};
      hn::StoreMaskBits(d, hit, bits);
      slot_hit = hn::LoadMaskBits(du, bits);
    }
    if constexpr (kOwnRow && !std::is_same_v<Real, float>) {  // float: dropped above
      slot_hit = hn::And(slot_hit, partner_slots());
    }
    hn::StoreU(hn::Compress(slots, slot_hit), du, out);
    home.out += hn::CountTrue(du, slot_hit);
  };
  // The homes of `homes` at the indices kHome... against the range [s, end): each vector is
  // loaded once for all of them.
  // Whole vectors under a mask fixed outside the loop, then the part-filled last one: no mask is
  // computed per vector.
  const auto whole = hn::FirstN(d, lanes);
  const auto step = static_cast<std::uint32_t>(lanes);
  auto test_range = [&]<int... kHome>(std::integer_sequence<int, kHome...>, HomeLanes * homes,
                                      std::uint32_t s, const std::uint32_t end,
                                      const auto own_row_tag) CONTACTLAB_INLINE {
    // The homes in a local copy for the range, written back after it: through `homes` GCC
    // stored every home's cursor to the stack at every vector (four stores in a loop of about
    // 70 instructions), 5 - 6 % of T_ALL on the paper and core scenes' full stencil.
    HomeLanes local[] = {homes[kHome]...};
    auto test_vector = [&](const auto valid, const auto whole_tag) CONTACTLAB_INLINE {
      constexpr bool kWhole = decltype(whole_tag)::value;
      auto load = [&](const Real* p) {
        if constexpr (kWhole) {
          return hn::LoadU(d, p + s);
        } else {  // AVX2 keeps a masked load a masked load even under an all-true mask
          return LoadFirst(d, valid, p + s, end - s);
        }
      };
      const V cx = load(px), cy = load(py), cz = load(pz);
      V cd = hn::Zero(d);
      if constexpr (kDiameters) cd = load(pd);
      (test_home(local[kHome], s, end, cx, cy, cz, cd, valid, whole_tag, own_row_tag), ...);
    };
    for (; end - s >= step; s += step) test_vector(whole, std::true_type{});  // s <= end
    if (s < end) test_vector(hn::FirstN(d, end - s), std::false_type{});
    ((homes[kHome].out = local[kHome].out), ...);
  };
  const auto all_homes = std::make_integer_sequence<int, kHomes>{};

  HomeLanes homes[kHomes];
  for (int b = 0; b < kHomes; ++b) {
    const std::uint32_t slot = task.homes[b];
    homes[b] = {hn::Set(d, px[slot]),
                hn::Set(d, py[slot]),
                hn::Set(d, pz[slot]),
                kDiameters ? hn::Set(d, pd[slot]) : hn::Zero(d),
                slot,
                task.out[b]};
  }
  for (int r = 0; r < task.count; ++r) {
    const SlotRange range = task.ranges[r];
    if (r != task.own) {
      test_range(all_homes, homes, range.begin, range.end, std::false_type{});
    } else {
      // The row of the homes' cell, for all homes at once, each dropping its own slot (and with
      // the half stencil the slots before it): a pass per home had loaded each vector once per
      // home, and a sparse cell's homes paid two part-filled vectors each.
      test_range(all_homes, homes, task.half ? homes[0].slot + 1 : range.begin, range.end,
                 std::true_type{});
    }
  }
  for (int b = 0; b < kHomes; ++b) {
    task.found[b] = static_cast<std::size_t>(homes[b].out - task.out[b]);
  }
}

template <bool kDiameters, class Real>
void AppendHomes(const BlockTask<Real>& task) {
  switch (task.home_count) {
    case 1:
      return AppendBlock<1, kDiameters>(task);
    case 2:
      return AppendBlock<2, kDiameters>(task);
    case 3:
      return AppendBlock<3, kDiameters>(task);
    default:
      static_assert(kBlockHomes == 4);
      return AppendBlock<4, kDiameters>(task);
  }
}

void AppendDouble(const BlockTask<double>& task) { AppendHomes<false>(task); }
void AppendDoubleDiameters(const BlockTask<double>& task) { AppendHomes<true>(task); }
void AppendFloat(const BlockTask<float>& task) { AppendHomes<false>(task); }
void AppendFloatDiameters(const BlockTask<float>& task) { AppendHomes<true>(task); }
std::int64_t Target() { return HWY_TARGET; }

}  // namespace HWY_NAMESPACE
}  // namespace contactlab::simd
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
#include <algorithm>
#include <atomic>
#include <cctype>
#include <cstdlib>
#include <mutex>

#include "contactlab/kernels/error.hpp"
#include "contactlab/kernels/simd.hpp"

namespace contactlab {
namespace simd {

HWY_EXPORT(AppendDouble);
HWY_EXPORT(AppendDoubleDiameters);
HWY_EXPORT(AppendFloat);
HWY_EXPORT(AppendFloatDiameters);
HWY_EXPORT(Target);

void append_contacts(const BlockTask<double>& task, bool diameters) {
  return diameters ? HWY_DYNAMIC_DISPATCH(AppendDoubleDiameters)(task)
                   : HWY_DYNAMIC_DISPATCH(AppendDouble)(task);
}
void append_contacts(const BlockTask<float>& task, bool diameters) {
  return diameters ? HWY_DYNAMIC_DISPATCH(AppendFloatDiameters)(task)
                   : HWY_DYNAMIC_DISPATCH(AppendFloat)(task);
}

namespace {

std::int64_t current_target() { return HWY_DYNAMIC_DISPATCH(Target)(); }

std::atomic<bool> scalar_only{false};
std::atomic<bool> named{false};
std::once_flag environment_read;

// The targets of the CPU and the build, read before any selection narrows what Highway reports.
const std::vector<std::int64_t>& available() {
  static const std::vector<std::int64_t> targets = hwy::SupportedAndGeneratedTargets();
  return targets;
}

std::string upper(std::string_view text) {
  std::string s(text);
  for (char& c : s) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return s;
}

void select(std::string_view name) {
  const std::string wanted = upper(name);
  if (wanted == "OFF") {
    scalar_only = true;
    named = false;
    return;
  }
  hwy::SetSupportedTargetsForTest(0);  // the CPU's own list again
  if (wanted == "BEST") {
    scalar_only = false;
    named = false;
    return;
  }
  for (const std::int64_t target : available()) {
    if (upper(hwy::TargetName(target)) == wanted) {
      hwy::SetSupportedTargetsForTest(target);
      scalar_only = false;
      named = true;
      return;
    }
  }
  std::string choices;
  for (const std::string& t : simd_targets()) choices += (choices.empty() ? "" : ", ") + t;
  throw InputError("SIMD target '" + std::string(name) +
                   "' is not available here (choices: best, " + choices + ")");
}

void read_environment() {
  available();
  std::call_once(environment_read, [] {
    if (const char* name = std::getenv("CONTACTLAB_SIMD")) {
      try {
        select(name);
      } catch (const InputError& e) {
        throw InputError(std::string("CONTACTLAB_SIMD: ") + e.what());
      }
    }
  });
}

}  // namespace
}  // namespace simd

std::string simd_target() {
  simd::read_environment();
  if (simd::scalar_only) return "off";
  return hwy::TargetName(simd::current_target());
}

std::vector<std::string> simd_targets() {
  std::vector<std::string> names;
  for (const std::int64_t target : simd::available()) {
    names.emplace_back(hwy::TargetName(target));
  }
  names.emplace_back("off");
  return names;
}

void select_simd_target(std::string_view name) {
  simd::read_environment();
  simd::select(name);
}

bool simd_enabled() {
  simd::read_environment();
  return !simd::scalar_only;
}

bool simd_forced() {
  simd::read_environment();
  return simd::named;
}

}  // namespace contactlab
#endif  // HWY_ONCE

#else  // CONTACTLAB_NO_SIMD: the scalar loop only (the program valgrind simulates: libhwy's
       // start-up code reads the time stamp counter with rdtscp, which valgrind cannot run).
#include "contactlab/kernels/error.hpp"
#include "contactlab/kernels/simd.hpp"

namespace contactlab {
namespace simd {
void append_contacts(const BlockTask<double>&, bool) {
  throw InputError("this build has no SIMD contact tests");
}
void append_contacts(const BlockTask<float>&, bool) {
  throw InputError("this build has no SIMD contact tests");
}
}  // namespace simd
std::string simd_target() { return "off"; }
std::vector<std::string> simd_targets() { return {"off"}; }
void select_simd_target(std::string_view name) {
  if (name != "off" && name != "best") {
    throw InputError("SIMD target '" + std::string(name) +
                     "' is not available here (choices: best, off: this build has no SIMD)");
  }
}
bool simd_enabled() { return false; }
bool simd_forced() { return false; }
}  // namespace contactlab
#endif  // CONTACTLAB_NO_SIMD
