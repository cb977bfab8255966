// Helpers shared by the kernel tests: building scenes by hand, comparing contact lists with
// readable diagnostics, an independent count of the candidate pair tests, temporary folders.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "contactlab/kernels/brute_force.hpp"
#include "contactlab/kernels/cell_grid.hpp"
#include "contactlab/kernels/contact_list.hpp"
#include "contactlab/kernels/detector.hpp"
#include "contactlab/kernels/pair_test.hpp"
#include "contactlab/kernels/rng.hpp"
#include "contactlab/kernels/scene.hpp"
#include "contactlab/kernels/scene_generate.hpp"
#include "contactlab/kernels/traverse.hpp"
#include "contactlab/kernels/variant.hpp"

namespace contactlab::test {

using Point = std::array<double, 3>;

inline Scene make_scene(const std::vector<Point>& points, const Box& box = Box{}) {
  Scene scene;
  scene.box = box;
  scene.reserve(points.size());
  for (const auto& p : points) {
    scene.x.push_back(p[0]);
    scene.y.push_back(p[1]);
    scene.z.push_back(p[2]);
  }
  return scene;
}

// The variants every equivalence test runs: 2 loops x 3 orders x 2 stencils x 2 precisions with
// the dense index and 10 schedules, and with the hashed index and 2 schedules (block and
// dynamic,7: the index changes where a stencil's ranges are found, not how a schedule divides
// the loop, and all 10 would double the cost of every suite that runs this list).
inline std::vector<Variant> every_variant() {
  VariantSpace dense = all_variants({1, 7, 64});
  dense.grids = {GridIndex::kDense};
  VariantSpace hashed = dense;
  hashed.grids = {GridIndex::kHashed};
  hashed.schedules = {Schedule{ScheduleKind::kStatic, 0}, Schedule{ScheduleKind::kDynamic, 7}};
  std::vector<Variant> variants = enumerate(dense);
  for (const Variant& v : enumerate(hashed)) variants.push_back(v);
  return variants;
}

// A few variants that between them cover every loop, order, stencil and precision, on the
// default (auto) grid index (for the expensive hard cases, where running all of them would cost
// time without covering more code).
inline std::vector<Variant> covering_variants() {
  VariantSpace space = all_variants({});
  space.grids = {GridIndex::kAuto};
  space.schedules = {Schedule{ScheduleKind::kDynamic, 7}};
  return enumerate(space);
}

inline std::vector<Variant> only(std::vector<Variant> variants, Precision precision) {
  std::erase_if(variants, [&](const Variant& v) { return v.precision != precision; });
  return variants;
}

// The brute force of brute_force.hpp with the pair test (pair_test.hpp) evaluated in float only,
// on coordinates relative to the box's lower corner: what the float variants would find without
// their second test in double (hard cases use it to show that they exercise that test).
inline ContactList float_brute_force(const Scene& scene, double diameter) {
  const std::size_t n = scene.size();
  std::vector<float> x(n), y(n), z(n), d(scene.diameter.size());
  for (std::size_t i = 0; i < n; ++i) {
    x[i] = static_cast<float>(scene.x[i] - scene.box.lo[0]);
    y[i] = static_cast<float>(scene.y[i] - scene.box.lo[1]);
    z[i] = static_cast<float>(scene.z[i] - scene.box.lo[2]);
    if (scene.has_diameters()) d[i] = static_cast<float>(scene.diameter[i]);
  }
  const float fd = static_cast<float>(diameter);
  const float reach_sq = fd * fd;
  ContactList list;
  list.offsets.assign(n + 1, 0);
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = 0; j < n; ++j) {
      if (i == j) continue;
      const float dx = x[i] - x[j], dy = y[i] - y[j], dz = z[i] - z[j];
      const bool touching = scene.has_diameters() ? in_contact(dx, dy, dz, d[i], d[j])
                                                  : in_contact(dx, dy, dz, reach_sq);
      if (touching) list.partners.push_back(static_cast<std::uint32_t>(j));
    }
    list.offsets[i + 1] = list.partners.size();
  }
  return list;
}

struct Detected {
  DetectRun run;
  ContactList contacts;  // canonical
};

inline Detected detect(const Scene& scene, const Variant& variant, double diameter, int threads) {
  ContactDetector detector;
  DetectOptions options;
  options.variant = variant;
  options.diameter = diameter;
  options.threads = threads;
  Detected result;
  result.run = detector.run(scene, options);
  result.contacts = detector.canonical_contacts();
  return result;
}

inline std::string row_text(const ContactList& list, std::size_t i) {
  std::ostringstream out;
  out << "[";
  const auto row = list.partners_of(i);
  for (std::size_t k = 0; k < row.size() && k < 12; ++k) out << (k ? " " : "") << row[k];
  if (row.size() > 12) out << " ... (" << row.size() << " partners)";
  out << "]";
  return out.str();
}

// Exact equality of two canonical contact lists, reporting the first rows that differ.
inline ::testing::AssertionResult same_contacts(const ContactList& got, const ContactList& want) {
  if (got == want) return ::testing::AssertionSuccess();
  auto failure = ::testing::AssertionFailure();
  if (got.particle_count() != want.particle_count()) {
    return failure << "particle count " << got.particle_count() << " != expected "
                   << want.particle_count();
  }
  failure << "contact lists differ: " << got.pair_count() << " pairs (" << got.partners.size()
          << " entries) vs expected " << want.pair_count() << " pairs (" << want.partners.size()
          << " entries)";
  int shown = 0;
  for (std::size_t i = 0; i < want.particle_count() && shown < 5; ++i) {
    const auto a = got.partners_of(i);
    const auto b = want.partners_of(i);
    if (!std::equal(a.begin(), a.end(), b.begin(), b.end())) {
      failure << "\n  particle " << i << ": got " << row_text(got, i) << ", expected "
              << row_text(want, i);
      ++shown;
    }
  }
  return failure;
}

// CSR well formed, rows strictly ascending, no self-contacts, and symmetric: j in row i iff i
// in row j.
inline ::testing::AssertionResult well_formed(const ContactList& list) {
  const std::size_t n = list.particle_count();
  if (list.offsets.empty() || list.offsets.front() != 0 ||
      list.offsets.back() != list.partners.size()) {
    return ::testing::AssertionFailure() << "offsets do not span the partner array";
  }
  if (list.partners.size() % 2 != 0) {
    return ::testing::AssertionFailure()
           << "odd number of partner entries " << list.partners.size();
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (list.offsets[i + 1] < list.offsets[i]) {
      return ::testing::AssertionFailure() << "offsets decrease at " << i;
    }
    const auto row = list.partners_of(i);
    for (std::size_t k = 0; k < row.size(); ++k) {
      const std::uint32_t j = row[k];
      if (j >= n) return ::testing::AssertionFailure() << "row " << i << " names particle " << j;
      if (j == i) return ::testing::AssertionFailure() << "self-contact of particle " << i;
      if (k > 0 && row[k - 1] >= j) {
        return ::testing::AssertionFailure() << "row " << i << " not strictly ascending";
      }
      const auto back = list.partners_of(j);
      if (!std::binary_search(back.begin(), back.end(), static_cast<std::uint32_t>(i))) {
        return ::testing::AssertionFailure()
               << "asymmetric: " << j << " in row " << i << " but not " << i << " in row " << j;
      }
    }
  }
  return ::testing::AssertionSuccess();
}

// Pair tests the full 27-cell stencil makes for each particle, counted independently of the
// detector: the particles of the (up to) 27 cells around its cell, less itself. The half
// stencil makes exactly half as many in total.
// The grid of a scene's detection in linear numbering, each particle's cell and each cell's
// particle count.
struct CellCounts {
  CellGrid grid;
  std::array<int, 3> dims;
  std::vector<std::uint64_t> count;      // by key
  std::vector<std::array<int, 3>> cell;  // by particle
};

inline CellCounts cell_counts(const Scene& scene, double diameter) {
  const double width = scene.has_diameters() ? scene.max_diameter() : diameter;
  CellCounts c{CellGrid(scene.box, width, CellNumbering::kLinear), {}, {}, {}};
  c.dims = c.grid.dims();
  c.count.assign(c.grid.cell_count(), 0);
  c.cell.resize(scene.size());
  for (std::size_t i = 0; i < scene.size(); ++i) {
    c.cell[i] = c.grid.coords_of(scene.x[i], scene.y[i], scene.z[i]);
    ++c.count[c.grid.key(c.cell[i][0], c.cell[i][1], c.cell[i][2])];
  }
  return c;
}

inline std::vector<std::uint64_t> expected_full_candidates_per_particle(const Scene& scene,
                                                                        double diameter) {
  const auto [grid, dims, count, cell] = cell_counts(scene, diameter);
  std::vector<std::uint64_t> tests(scene.size(), 0);
  for (std::size_t i = 0; i < scene.size(); ++i) {
    for (int dz = -1; dz <= 1; ++dz) {
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          const int cx = cell[i][0] + dx, cy = cell[i][1] + dy, cz = cell[i][2] + dz;
          if (cx < 0 || cy < 0 || cz < 0 || cx >= dims[0] || cy >= dims[1] || cz >= dims[2])
            continue;
          tests[i] += count[grid.key(cx, cy, cz)];
        }
      }
    }
    tests[i] -= 1;  // not itself
  }
  return tests;
}

inline std::uint64_t expected_full_candidates(const Scene& scene, double diameter) {
  std::uint64_t total = 0;
  for (const auto t : expected_full_candidates_per_particle(scene, diameter)) total += t;
  return total;
}

// The candidates of the particle loop over sorted particles when sparse cells share their
// ranges as tiles (DetectRun::tiled), from the cell occupancy and the rule of traverse.hpp's
// find_tile: the aligned group of traversal::kTileCells cells along x holding a cell is its tile
// if it holds at most simd::kBlockHomes particles, else the group's half holding it, and so on
// down to the cell alone. A tile's rows reach from its first cell's x - 1 to its last one's
// x + 1; the half stencil's own row starts at its first cell.
struct TiledCandidates {
  std::vector<std::uint64_t> full_per_particle;
  std::uint64_t full = 0, half = 0;
  std::uint64_t tiles = 0;
};

inline TiledCandidates expected_tiled_candidates(const Scene& scene, double diameter) {
  constexpr int kCells = traversal::kTileCells;
  constexpr std::uint64_t kLimit = 4;  // simd::kBlockHomes
  // Named references, not a structured binding: the lambdas capture them, which clang before 16
  // (clang-tidy) does not allow of structured bindings.
  const CellCounts counts = cell_counts(scene, diameter);
  const auto& grid = counts.grid;
  const auto& dims = counts.dims;
  const auto& count = counts.count;
  const auto& cell = counts.cell;
  // Particles in cells x_lo..x_hi (clipped) of row (cy, cz).
  auto row = [&](int x_lo, int x_hi, int cy, int cz) {
    std::uint64_t sum = 0;
    if (cy < 0 || cz < 0 || cy >= dims[1] || cz >= dims[2]) return sum;
    for (int cx = std::max(x_lo, 0); cx <= std::min(x_hi, dims[0] - 1); ++cx)
      sum += count[grid.key(cx, cy, cz)];
    return sum;
  };
  auto tile_of = [&](int cx, int cy, int cz) -> std::array<int, 2> {
    if (count[grid.key(cx, cy, cz)] > kLimit) return {cx, cx};
    for (int size = kCells; size > 1; size /= 2) {
      const int first = cx - cx % size, last = std::min(first + size, dims[0]) - 1;
      if (row(first, last, cy, cz) <= kLimit) return {first, last};
    }
    return {cx, cx};
  };
  TiledCandidates result;
  std::set<std::array<int, 4>> tiles;  // first, last, cy, cz
  result.full_per_particle.resize(scene.size());
  for (std::size_t i = 0; i < scene.size(); ++i) {
    const auto [cx, cy, cz] = cell[i];
    const auto [first, last] = tile_of(cx, cy, cz);
    tiles.insert({first, last, cy, cz});
    std::uint64_t tests = 0;
    for (int dz = -1; dz <= 1; ++dz) {
      for (int dy = -1; dy <= 1; ++dy) tests += row(first - 1, last + 1, cy + dy, cz + dz);
    }
    result.full_per_particle[i] = tests - 1;  // not itself
    result.full += tests - 1;
  }
  for (const auto& [first, last, cy, cz] : tiles) {
    // The tile's particles are the first of its own row, in slot order.
    const std::uint64_t homes = row(first, last, cy, cz);
    const std::uint64_t forward =
        row(first - 1, last + 1, cy + 1, cz) + row(first - 1, last + 1, cy - 1, cz + 1) +
        row(first - 1, last + 1, cy, cz + 1) + row(first - 1, last + 1, cy + 1, cz + 1);
    const std::uint64_t own = row(first, last + 1, cy, cz);
    for (std::uint64_t p = 0; p < homes; ++p) result.half += forward + own - p - 1;
  }
  result.tiles = tiles.size();
  return result;
}

// A permutation of 0..n-1 from a fixed seed (Fisher-Yates on xoshiro: the same on every
// standard library, unlike std::shuffle).
inline std::vector<std::uint32_t> permutation(std::size_t n, std::uint64_t seed) {
  std::vector<std::uint32_t> perm(n);
  for (std::size_t i = 0; i < n; ++i) perm[i] = static_cast<std::uint32_t>(i);
  Xoshiro256 rng(seed);
  for (std::size_t i = n; i > 1; --i) {
    const std::size_t j = static_cast<std::size_t>(rng.next() % i);
    std::swap(perm[i - 1], perm[j]);
  }
  return perm;
}

// Canonical contact list from a set of unordered pairs.
inline ContactList list_from_pairs(
    std::size_t n, const std::vector<std::pair<std::uint32_t, std::uint32_t>>& pairs) {
  std::vector<std::vector<std::uint32_t>> rows(n);
  for (const auto& [i, j] : pairs) {
    rows[i].push_back(j);
    rows[j].push_back(i);
  }
  ContactList list;
  list.offsets.assign(n + 1, 0);
  for (std::size_t i = 0; i < n; ++i) {
    std::sort(rows[i].begin(), rows[i].end());
    list.offsets[i + 1] = list.offsets[i] + rows[i].size();
    list.partners.insert(list.partners.end(), rows[i].begin(), rows[i].end());
  }
  return list;
}

// A fresh empty folder under the test temporary directory, removed at the end of its scope.
class TempDir {
 public:
  TempDir() {
    namespace fs = std::filesystem;
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string name = "contactlab_";
    if (info) name += std::string(info->test_suite_name()) + "_" + info->name();
    for (auto& c : name) {
      if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_') c = '_';
    }
    name += "_" + std::to_string(::getpid());  // two builds may run the same test at once
    path_ = fs::path(::testing::TempDir()) / name;
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  const std::filesystem::path& path() const { return path_; }
  std::string file(const std::string& name) const { return (path_ / name).string(); }
  // Names of the entries in the folder, sorted.
  std::vector<std::string> entries() const {
    std::vector<std::string> names;
    for (const auto& entry : std::filesystem::directory_iterator(path_)) {
      names.push_back(entry.path().filename().string());
    }
    std::sort(names.begin(), names.end());
    return names;
  }

 private:
  std::filesystem::path path_;
};

inline void write_text(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << text;
}

inline std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

}  // namespace contactlab::test
