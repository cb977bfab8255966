// Contact detection: one traversal skeleton shared by every variant. The variant picks the
// layout (sorted coordinates or indirection through cell lists), the outer loop (cells or
// particles), the stencil (27 cells or own cell + 13 forward) and the OpenMP schedule.
#include "contactlab/kernels/detector.hpp"

#include <omp.h>

#include <algorithm>
#include <cstring>
#include <type_traits>

#include "contactlab/kernels/error.hpp"
#include "contactlab/kernels/pair_test.hpp"

namespace contactlab {

int resolve_threads(int requested) { return requested > 0 ? requested : omp_get_max_threads(); }
namespace {

// The stencil as rows of cells along x: for each (dy, dz) the cells dx in [dx_lo, dx_hi].
// With the linear numbering a row's cells are consecutive keys, so its particles are one slot
// range found with two loads. Rows are in ascending key order (z, then y).
struct StencilRow {
  int dy, dz, dx_lo, dx_hi;
};

struct StencilRows {
  std::array<StencilRow, 9> rows{};
  int count = 0;
  int own = 0;  // the row holding the home cell
};

StencilRows make_stencil(Stencil stencil) {
  StencilRows result;
  for (int dz = -1; dz <= 1; ++dz) {
    for (int dy = -1; dy <= 1; ++dy) {
      // Forward half: own cell and the cells (dz, dy, dx) lexicographically after (0, 0, 0),
      // so each unordered pair of distinct neighbour cells is visited from one of them only.
      const bool before_own = dz < 0 || (dz == 0 && dy < 0);
      if (stencil == Stencil::kHalf && before_own) continue;
      const bool own = dz == 0 && dy == 0;
      if (own) result.own = result.count;
      const int dx_lo = stencil == Stencil::kHalf && own ? 0 : -1;
      result.rows[result.count++] = {dy, dz, dx_lo, 1};
    }
  }
  return result;
}

struct SlotRange {
  std::uint32_t begin, end;
};

// The particles of a home cell's stencil as slot ranges, ranges[own] holding the home cell.
// With the half stencil ranges[own] starts at the home cell (no stencil cell precedes it).
struct NeighbourRanges {
  std::array<SlotRange, 27> ranges{};
  int count = 0;
  int own = 0;
  std::uint64_t candidates = 0;  // slots in all ranges, the home particle's own included

  // Pair tests of the home particle in slot s_h: with the half stencil only the own range's
  // later slots, with the full one every slot but its own.
  std::uint64_t tests_from(std::uint32_t s_h, bool half) const {
    return candidates - (half ? s_h + 1 - ranges[own].begin : 1);
  }

  void build(const CellGrid& grid, const CellRegistry& registry, const StencilRows& stencil,
             const std::array<int, 3>& home) {
    count = 0;
    candidates = 0;
    const auto& dims = grid.dims();
    const std::uint32_t* begin_of = registry.cell_begin.data();
    const bool linear = grid.numbering() == CellNumbering::kLinear;
    for (int r = 0; r < stencil.count; ++r) {
      const StencilRow& row = stencil.rows[r];
      const int cy = home[1] + row.dy, cz = home[2] + row.dz;
      if (cy < 0 || cz < 0 || cy >= dims[1] || cz >= dims[2]) continue;
      const int x_lo = std::max(home[0] + row.dx_lo, 0);
      const int x_hi = std::min(home[0] + row.dx_hi, dims[0] - 1);
      if (linear) {
        if (r == stencil.own) own = count;
        const SlotRange range{begin_of[grid.key(x_lo, cy, cz)],
                              begin_of[grid.key(x_hi, cy, cz) + 1]};
        if (range.begin == range.end) continue;  // never the own row: it holds the home
        ranges[count++] = range;
        candidates += range.end - range.begin;
        continue;
      }
      // Morton keys of a row are not consecutive: one range per cell.
      for (int cx = x_lo; cx <= x_hi; ++cx) {
        const std::uint32_t key = grid.key(cx, cy, cz);
        const SlotRange range{begin_of[key], begin_of[key + 1]};
        if (range.begin == range.end) continue;  // never the home cell
        if (r == stencil.own && cx == home[0]) own = count;
        ranges[count++] = range;
        candidates += range.end - range.begin;
      }
    }
  }
};

// Where the kernel reads particles. `cell_x/y/z` are the double coordinates the particles
// were registered with (a home particle's cell must be found exactly as registration did);
// `x/y/z/d` are the coordinates the pair test reads, in the variant's precision T.
template <class T>
struct Coordinates {
  const double *cell_x, *cell_y, *cell_z;
  const T *x, *y, *z, *d;
};

// Coordinates stored in slot order: working id == slot, no indirection.
template <class T>
struct SortedLayout : Coordinates<T> {
  using Real = T;
  std::uint32_t particle_at(std::uint32_t slot) const { return slot; }
  std::uint32_t slot_of(std::uint32_t particle) const { return particle; }
};

// Coordinates in input order: cell lists map slots to input ids (the paper's unsorted case).
template <class T>
struct UnsortedLayout : Coordinates<T> {
  using Real = T;
  const std::uint32_t* slot_particle;
  const std::uint32_t* particle_slot;
  std::uint32_t particle_at(std::uint32_t slot) const { return slot_particle[slot]; }
  std::uint32_t slot_of(std::uint32_t particle) const { return particle_slot[particle]; }
};

// Tests home particle h (in slot s_h) against the candidate ranges, appending partners.
template <class Layout, bool kHalf, bool kDiameters>
inline void test_home(const Layout& layout, const NeighbourRanges& nb, std::uint32_t h,
                      std::uint32_t s_h, typename Layout::Real reach_sq,
                      detail::PartnerBuffer& out) {
  using Real = typename Layout::Real;
  const Real xi = layout.x[h], yi = layout.y[h], zi = layout.z[h];
  const Real di = kDiameters ? layout.d[h] : Real(0);
  auto test_range = [&](std::uint32_t begin, std::uint32_t end) {
    if (begin >= end) return;
    std::uint32_t* next = out.tail(end - begin);
    std::size_t found = 0;
    for (std::uint32_t s = begin; s < end; ++s) {
      const std::uint32_t j = layout.particle_at(s);
      const Real dx = xi - layout.x[j], dy = yi - layout.y[j], dz = zi - layout.z[j];
      bool touching;
      if constexpr (kDiameters) {
        touching = in_contact(dx, dy, dz, di, layout.d[j]);
      } else {
        touching = in_contact(dx, dy, dz, reach_sq);
      }
      next[found] = j;
      found += touching;
    }
    out.advance(found);
  };
  for (int r = 0; r < nb.count; ++r) {
    const SlotRange range = nb.ranges[r];
    if (r != nb.own) {
      test_range(range.begin, range.end);
    } else if constexpr (kHalf) {
      // The range starts at the home cell: only its later slots and the cells after it.
      test_range(s_h + 1, range.end);
    } else {
      test_range(range.begin, s_h);
      test_range(s_h + 1, range.end);
    }
  }
}

omp_sched_t to_omp(ScheduleKind kind) {
  switch (kind) {
    case ScheduleKind::kStatic:
      return omp_sched_static;
    case ScheduleKind::kDynamic:
      return omp_sched_dynamic;
    case ScheduleKind::kGuided:
      return omp_sched_guided;
  }
  return omp_sched_static;
}

template <class F>
void dispatch_bool(bool value, F&& f) {
  if (value) {
    f(std::true_type{});
  } else {
    f(std::false_type{});
  }
}

}  // namespace

template <class Layout>
void ContactDetector::detect(const CellGrid& grid, const Layout& layout,
                             const DetectOptions& options, DetectRun& run) {
  const Variant& variant = options.variant;
  const std::uint32_t n = static_cast<std::uint32_t>(registry_.slot_particle.size());
  const int threads = run.threads;
  const bool half = variant.stencil == Stencil::kHalf;
  const bool diameters = layout.d != nullptr;
  const StencilRows stencil = make_stencil(variant.stencil);
  using Real = typename Layout::Real;
  const Real diameter = static_cast<Real>(options.diameter);
  const Real reach_sq = diameter * diameter;

  if (thread_partners_.size() < static_cast<std::size_t>(threads)) {
    thread_partners_.resize(threads);
    thread_homes_.resize(threads);
  }
  found_count_.resize(n);
  // Half stencil: reverse_count_[t * n + j] counts the finds (h, j) of thread t, later the
  // start of thread t's share of row j's reverse entries. Per-thread counts avoid atomics.
  if (half) reverse_count_.resize(std::size_t{n} * threads);
  contacts_.offsets.resize(std::size_t{n} + 1);
  run.thread_busy_s.assign(threads, 0.0);
  std::vector<std::uint64_t> thread_tests(threads, 0);

  omp_set_schedule(to_omp(variant.schedule.kind), variant.schedule.chunk);
  if (options.observer) options.observer->region_begin(threads);
  const double start = omp_get_wtime();

#pragma omp parallel num_threads(threads)
  {
    const int tid = omp_get_thread_num();
    detail::PartnerBuffer& out = thread_partners_[tid];
    std::vector<std::uint32_t>& homes = thread_homes_[tid];
    out.clear();
    homes.clear();
    std::uint64_t tests = 0;
    NeighbourRanges nb;

    auto visit = [&](auto half_tag, auto diameters_tag, std::uint32_t h, std::uint32_t s_h) {
      const std::size_t before = out.size();
      test_home<Layout, decltype(half_tag)::value, decltype(diameters_tag)::value>(
          layout, nb, h, s_h, reach_sq, out);
      found_count_[h] = static_cast<std::uint32_t>(out.size() - before);
      homes.push_back(h);
      tests += nb.tests_from(s_h, decltype(half_tag)::value);
    };

    if (options.observer) options.observer->thread_begin(tid);
    const double loop_start = omp_get_wtime();
    dispatch_bool(half, [&](auto half_tag) {
      dispatch_bool(diameters, [&](auto diameters_tag) {
        if (variant.loop == LoopKind::kParticle) {
          std::uint32_t cached_key = UINT32_MAX;
#pragma omp for schedule(runtime) nowait
          for (std::uint32_t h = 0; h < n; ++h) {
            const auto home = grid.coords_of(layout.cell_x[h], layout.cell_y[h], layout.cell_z[h]);
            const std::uint32_t key = grid.key(home[0], home[1], home[2]);
            if (key != cached_key) {
              nb.build(grid, registry_, stencil, home);
              cached_key = key;
            }
            visit(half_tag, diameters_tag, h, layout.slot_of(h));
          }
        } else {
          const std::uint64_t keys = grid.key_count();
#pragma omp for schedule(runtime) nowait
          for (std::uint64_t key = 0; key < keys; ++key) {
            const std::uint32_t begin = registry_.cell_begin[key];
            const std::uint32_t end = registry_.cell_begin[key + 1];
            if (begin == end) continue;
            const std::uint32_t first = layout.particle_at(begin);
            nb.build(
                grid, registry_, stencil,
                grid.coords_of(layout.cell_x[first], layout.cell_y[first], layout.cell_z[first]));
            for (std::uint32_t s = begin; s < end; ++s) {
              visit(half_tag, diameters_tag, layout.particle_at(s), s);
            }
          }
        }
      });
    });
    run.thread_busy_s[tid] = omp_get_wtime() - loop_start;
    thread_tests[tid] = tests;
    if (options.observer) options.observer->thread_end(tid);

    // Assemble the rows: row h = h's own finds, then (half stencil) every find (g, h) made
    // from another particle g, grouped by the thread that made it.
    std::uint32_t* const reverse = half ? reverse_count_.data() + std::size_t{n} * tid : nullptr;
    if (half) {
      std::fill(reverse, reverse + n, 0u);
      for (const std::uint32_t j : std::span(out.data(), out.size())) ++reverse[j];
    }
#pragma omp barrier
#pragma omp single
    {
      std::uint64_t total = 0;
      contacts_.offsets[0] = 0;
      for (std::uint32_t i = 0; i < n; ++i) {
        std::uint32_t row = found_count_[i];
        if (half) {
          // Exclusive prefix over threads: where each thread's reverse entries of row i start.
          for (int t = 0; t < threads; ++t) {
            std::uint32_t& count = reverse_count_[std::size_t{n} * t + i];
            const std::uint32_t share = count;
            count = row;
            row += share;
          }
        }
        total += row;
        contacts_.offsets[i + 1] = total;
      }
      contacts_.partners.resize(total);
    }
    std::uint32_t* const partners = contacts_.partners.data();
    const std::uint32_t* found = out.data();
    for (const std::uint32_t h : homes) {
      const std::uint32_t count = found_count_[h];
      if (count == 0) continue;
      std::memcpy(partners + contacts_.offsets[h], found, count * sizeof(std::uint32_t));
      if (half) {
        for (std::uint32_t k = 0; k < count; ++k) {
          const std::uint32_t j = found[k];
          partners[contacts_.offsets[j] + reverse[j]++] = h;
        }
      }
      found += count;
    }
  }
  run.detect_s = omp_get_wtime() - start;
  if (options.observer) options.observer->region_end();
  run.candidate_tests = 0;
  for (const auto t : thread_tests) run.candidate_tests += t;
  run.contact_pairs = contacts_.pair_count();
}

// Validates the options, builds the grid and registers (and for sorted orders reorders) the
// particles: the paper's T_s.
CellGrid ContactDetector::prepare(const Scene& scene, const DetectOptions& options,
                                  DetectRun& run) {
  const bool diameters = scene.has_diameters();
  if (!diameters && !(options.diameter > 0.0 && options.diameter < 1e300)) {
    throw InputError("diameter D must be a positive finite number (got " +
                     std::to_string(options.diameter) + ")");
  }
  const Schedule& schedule = options.variant.schedule;
  if (schedule.chunk < 0 || (schedule.kind != ScheduleKind::kStatic && schedule.chunk == 0)) {
    throw InputError("schedule " + to_string(schedule) + ": chunk size must be >= 1");
  }
  if (scene.size() >= UINT32_MAX) throw InputError("at most 2^32 - 2 particles are supported");

  run.threads = resolve_threads(options.threads);
  const Order order = options.variant.order;
  const CellGrid grid(scene.box, diameters ? scene.max_diameter() : options.diameter,
                      order == Order::kMorton ? CellNumbering::kMorton : CellNumbering::kLinear);
  run.grid_dims = grid.dims();

  const double setup_start = omp_get_wtime();
  working_is_sorted_ = order != Order::kUnsorted;
  registry_.assign(grid, scene, working_is_sorted_ ? &sorted_ : nullptr);
  run.setup_s = omp_get_wtime() - setup_start;
  run.max_cell_occupancy = registry_.max_occupancy;
  return grid;
}

DetectRun ContactDetector::run(const Scene& scene, const DetectOptions& options) {
  DetectRun run;
  const CellGrid grid = prepare(scene, options, run);
  const Scene& source = working_is_sorted_ ? sorted_ : scene;  // coordinates in working order
  const bool diameters = scene.has_diameters();
  auto run_with = [&](const auto& coordinates) {
    if (working_is_sorted_) {
      using Real = std::remove_cvref_t<decltype(*coordinates.x)>;
      detect(grid, SortedLayout<Real>{coordinates}, options, run);
    } else {
      using Real = std::remove_cvref_t<decltype(*coordinates.x)>;
      detect(grid,
             UnsortedLayout<Real>{coordinates, registry_.slot_particle.data(),
                                  registry_.particle_slot.data()},
             options, run);
    }
  };
  if (options.variant.precision == Precision::kDouble) {
    run_with(Coordinates<double>{source.x.data(), source.y.data(), source.z.data(), source.x.data(),
                                 source.y.data(), source.z.data(),
                                 diameters ? source.diameter.data() : nullptr});
  } else {
    // Single precision, relative to the box's lower corner (absolute coordinates far from the
    // origin would lose most of their float digits). The conversion is part of the setup, as a
    // code keeping float coordinates would do it once when they change.
    const double convert_start = omp_get_wtime();
    const std::size_t n = source.size();
    const auto& lo = scene.box.lo;
    narrow_x_.resize(n);
    narrow_y_.resize(n);
    narrow_z_.resize(n);
    narrow_d_.resize(diameters ? n : 0);
#pragma omp parallel for schedule(static) num_threads(run.threads)
    for (std::size_t i = 0; i < n; ++i) {
      narrow_x_[i] = static_cast<float>(source.x[i] - lo[0]);
      narrow_y_[i] = static_cast<float>(source.y[i] - lo[1]);
      narrow_z_[i] = static_cast<float>(source.z[i] - lo[2]);
      if (diameters) narrow_d_[i] = static_cast<float>(source.diameter[i]);
    }
    run.setup_s += omp_get_wtime() - convert_start;
    run_with(Coordinates<float>{source.x.data(), source.y.data(), source.z.data(), narrow_x_.data(),
                                narrow_y_.data(), narrow_z_.data(),
                                diameters ? narrow_d_.data() : nullptr});
  }
  return run;
}

LoopWork ContactDetector::iteration_work(const Scene& scene, const DetectOptions& options) {
  DetectRun run;
  const CellGrid grid = prepare(scene, options, run);
  const Variant& variant = options.variant;
  const StencilRows stencil = make_stencil(variant.stencil);
  const bool half = variant.stencil == Stencil::kHalf;
  // The home particle's cell and slot, whichever the order: registration already knows them.
  const Scene& coordinates = working_is_sorted_ ? sorted_ : scene;
  auto slot_of = [&](std::uint32_t h) {
    return working_is_sorted_ ? h : registry_.particle_slot[h];
  };
  NeighbourRanges nb;
  auto tests_of = [&](std::uint32_t s_h) {
    return static_cast<std::uint32_t>(nb.tests_from(s_h, half));
  };
  LoopWork work;
  const std::uint32_t n = static_cast<std::uint32_t>(scene.size());
  if (variant.loop == LoopKind::kParticle) {
    work.tests.resize(n);
    work.homes.assign(n, 1);
    work.builds.resize(n);
    std::uint32_t previous_key = UINT32_MAX;
    for (std::uint32_t h = 0; h < n; ++h) {
      const auto home = grid.coords_of(coordinates.x[h], coordinates.y[h], coordinates.z[h]);
      const std::uint32_t key = grid.key(home[0], home[1], home[2]);
      nb.build(grid, registry_, stencil, home);
      work.tests[h] = tests_of(slot_of(h));
      work.builds[h] = key != previous_key ? 1 : 0;
      previous_key = key;
    }
  } else {
    work.tests.assign(grid.key_count(), 0);
    work.homes.assign(grid.key_count(), 0);
    work.builds.assign(grid.key_count(), 0);
    for (std::uint64_t key = 0; key < grid.key_count(); ++key) {
      const std::uint32_t begin = registry_.cell_begin[key], end = registry_.cell_begin[key + 1];
      if (begin == end) continue;
      const std::uint32_t first = registry_.slot_particle[begin];
      nb.build(grid, registry_, stencil,
               grid.coords_of(scene.x[first], scene.y[first], scene.z[first]));
      for (std::uint32_t s = begin; s < end; ++s) work.tests[key] += tests_of(s);
      work.homes[key] = end - begin;
      work.builds[key] = 1;
    }
  }
  return work;
}

}  // namespace contactlab
