// Contact detection, per-iteration work and neighbour lists: each is the traversal of
// traverse.hpp with its own pair op (src/pair_ops.hpp: ContactOp with the contact or the neighbour
// test, or WorkCountOp), and the CSR rows are assembled after the traversal.
#include "contactlab/kernels/detector.hpp"

#include <omp.h>

#include <algorithm>
#include <cstring>
#include <new>
#include <type_traits>

#include "contactlab/kernels/error.hpp"
#include "contactlab/kernels/simd.hpp"
#include "contactlab/kernels/traverse.hpp"
#include "src/pair_ops.hpp"

namespace contactlab {

int resolve_threads(int requested) { return requested > 0 ? requested : omp_get_max_threads(); }

bool writes_first_rows_in_place(const Variant& variant, int threads) {
  const bool rows_in_visiting_order =
      variant.loop == LoopKind::kParticle || variant.order != Order::kUnsorted;
  // The block and the balanced schedule give thread 0 the first iterations.
  const bool first_iterations =
      threads == 1 || variant.schedule.kind == ScheduleKind::kBalanced ||
      (variant.schedule.kind == ScheduleKind::kStatic && variant.schedule.chunk == 0);
  return variant.stencil == Stencil::kFull && rows_in_visiting_order && first_iterations;
}

double copied_output_share(const Variant& variant, int threads) {
  return writes_first_rows_in_place(variant, threads) ? 1.0 - 1.0 / threads : 1.0;
}

bool passes_reverse_entries_on(const Variant& variant, int threads) {
  const Schedule& schedule = variant.schedule;
  const bool homes_in_runs = variant.order != Order::kUnsorted &&
                             (schedule.kind == ScheduleKind::kBalanced ||
                              (schedule.kind == ScheduleKind::kStatic && schedule.chunk == 0));
  return variant.stencil == Stencil::kHalf && threads > 1 && !homes_in_runs;
}

namespace {

using pair_ops::ContactOp;
using pair_ops::ContactTest;
using pair_ops::NeighborTest;
using pair_ops::SimdContactTest;
using pair_ops::WorkCountOp;

omp_sched_t to_omp(ScheduleKind kind) {
  switch (kind) {
    case ScheduleKind::kStatic:
    case ScheduleKind::kBalanced:  // not an omp for: the traversal cuts its own blocks
      return omp_sched_static;
    case ScheduleKind::kDynamic:
      return omp_sched_dynamic;
    case ScheduleKind::kGuided:
      return omp_sched_guided;
  }
  return omp_sched_static;
}

}  // namespace

// The contact lists of a prepared grid: the traversal with a ContactOp per thread, then
// assemble_rows. Timing and observer hooks wrap the traversal only.
template <class Layout, class PairTest>
void ContactDetector::detect(const CellGrid& grid, const Layout& layout, const PairTest& test,
                             const DetectOptions& options, DetectRun& run) {
  const Variant& variant = options.variant;
  const std::uint32_t n = static_cast<std::uint32_t>(registry_.slot_particle.size());
  const int threads = run.threads;
  const bool half = variant.stencil == Stencil::kHalf;
  // Tiles of sparse cells where the homes are tested in blocks (SimdContactTest).
  const std::uint32_t tile_homes = ContactOp<PairTest>::kBlockHomes > 1 ? simd::kBlockHomes : 0;
  const bool balanced = variant.schedule.kind == ScheduleKind::kBalanced && run.threads > 1;
  if (balanced) balanced_blocks_.prepare(run.threads);
  const traversal::Spec spec{
      grid,          registry_,      variant.loop, variant.stencil,
      options.homes, options.blocks, tile_homes,   balanced ? &balanced_blocks_ : nullptr};

  if (thread_out_.size() < static_cast<std::size_t>(threads)) thread_out_.resize(threads);
  found_count_.resize(n);
  // Ghosts are never homes: their own finds stay 0.
  if (!spec.homes.covers(n) || !spec.blocks.all())
    std::fill(found_count_.begin(), found_count_.end(), 0u);
  if (half) {
    reverse_count_.resize(n);
    row_block_.assign(threads + 1, 0);
    home_run_.assign(2 * std::size_t(threads), 0);
    if (own_until_.size() < static_cast<std::size_t>(threads)) {
      own_until_ = std::vector<std::atomic<std::uint64_t>>(threads);
    }
    for (auto& until : own_until_) until.store(kOwnUntilUnknown, std::memory_order_relaxed);
  }
  contacts_.offsets.resize(std::size_t{n} + 1);
  range_sums_.assign(threads, 0);
  run.thread_busy_s.assign(threads, 0.0);
  std::vector<std::uint64_t>& thread_tests = run.thread_tests;
  thread_tests.assign(threads, 0);
  run.thread_homes.assign(threads, 0);
  // Where thread 0's finds are the first rows as they stand, it writes them into the contact
  // list's storage: 110 MB not copied on the paper's scene at one thread. The storage is
  // reserved for the larger of the last run's entries (plus what its last homes may append: a
  // block of them, each with the candidates of the nine rows of the longest tile, every cell the
  // fullest) and twice the entries the cell occupancies lead one to expect (about
  // 27 (sum occupancy^2 - n) candidates, 0.155 of them within a sphere of diameter D in cells at
  // least D wide: a first run's room); address space only until written. A scene with more moves
  // thread 0 to a buffer of its own.
  const bool rows_in_place = writes_first_rows_in_place(variant, threads);
  if (rows_in_place) {
    const double candidates = 27.0 * static_cast<double>(registry_.occupancy_squares - n);
    const std::size_t wanted =
        std::max(contacts_.partners.size() +
                     simd::kBlockHomes *
                         (std::size_t{9} * (traversal::kTileCells + 2) * registry_.max_occupancy) +
                     simd::kAppendSlack,
                 static_cast<std::size_t>(2.0 * 0.155 * candidates));
    if (contacts_.partners.capacity() < wanted) {
      contacts_.partners.clear();  // the last run's rows need not move along
      try {
        contacts_.partners.reserve(wanted);
      } catch (const std::bad_alloc&) {  // too large to reserve here: copied as before
      }
    }
    contacts_.partners.resize(contacts_.partners.capacity());
  }

  omp_set_schedule(to_omp(variant.schedule.kind), variant.schedule.chunk);
  if (options.observer) options.observer->region_begin(threads);
  const double start = omp_get_wtime();

#pragma omp parallel num_threads(threads)
  {
    const int tid = omp_get_thread_num();
    detail::ThreadOutput& mine = thread_out_[tid];
    if (tid == 0 && rows_in_place) {
      mine.partners.borrow(contacts_.partners.data(), contacts_.partners.size());
    } else {
      mine.partners.stop_borrowing();
    }
    mine.homes.clear();
    ContactOp<PairTest> op(test, mine, found_count_.data());
    if (options.observer) options.observer->thread_begin(tid);
    const double loop_start = omp_get_wtime();
    traversal::traverse(spec, layout, op);
    op.homes_done();
    run.thread_busy_s[tid] = omp_get_wtime() - loop_start;
    thread_tests[tid] = op.tests();
    run.thread_homes[tid] = mine.homes.size();
    if (options.observer) options.observer->thread_end(tid);
    assemble_rows(tid, threads, half, rows_in_place);
  }
  run.detect_s = omp_get_wtime() - start;
  run.weigh_s = balanced ? balanced_blocks_.weigh_seconds() : 0.0;
  if (options.observer) options.observer->region_end();
  run.candidate_tests = 0;
  for (const auto t : thread_tests) run.candidate_tests += t;
  run.tiled = traversal::uses_tiles(spec);
  run.contact_pairs = contacts_.pair_count();
}

// Validates the options, builds the grid (cells at least the largest reach, D or the largest
// diameter, plus skin wide) and registers (and for sorted orders reorders) the particles: the
// paper's T_s.
CellGrid ContactDetector::prepare(const Scene& scene, const DetectOptions& options, double skin,
                                  DetectRun& run) {
  const bool diameters = scene.has_diameters();
  if (!diameters && !(options.diameter > 0.0 && options.diameter < 1e300)) {
    throw InputError("diameter D must be a positive finite number (got " +
                     number_text(options.diameter) + ")");
  }
  const Schedule& schedule = options.variant.schedule;
  if (!has_valid_chunk(schedule)) {
    throw InputError("schedule " + to_string(schedule) +
                     (schedule.kind == ScheduleKind::kBalanced ? ": balanced takes no chunk size"
                                                               : ": chunk size must be >= 1"));
  }
  if (scene.size() >= UINT32_MAX) throw InputError("at most 2^32 - 2 particles are supported");
  if (!options.blocks.all() && options.blocks.index >= options.blocks.count) {
    throw InputError("home blocks: index " + std::to_string(options.blocks.index) +
                     " is not below the count " + std::to_string(options.blocks.count));
  }
  if (options.homes.first > options.homes.last) {
    throw InputError("home range: first " + std::to_string(options.homes.first) + " is past last " +
                     std::to_string(options.homes.last));
  }

  run.threads = resolve_threads(options.threads);
  const Order order = options.variant.order;
  const double width = (diameters ? scene.max_diameter() : options.diameter) + skin;
  const CellGrid grid(scene.box, std::max(width, options.min_cell_width),
                      order == Order::kMorton ? CellNumbering::kMorton : CellNumbering::kLinear);
  run.grid_dims = grid.dims();

  const double setup_start = omp_get_wtime();
  working_is_sorted_ = order != Order::kUnsorted;
  registry_.assign(grid, scene, working_is_sorted_ ? &working_ : nullptr, run.threads,
                   use_hashed_index(options.variant.grid, grid, scene.size()));
  const double copy_start = omp_get_wtime();
  working_is_copy_ = !working_is_sorted_ && options.variant.precision == Precision::kDouble &&
                     copy_for_random_reads(scene);
  if (working_is_copy_) copy_in_input_order(scene, run.threads);
  run.setup_s = omp_get_wtime() - setup_start;
  run.registration_s = registry_.registration_s;
  run.reorder_s = registry_.reorder_s + (omp_get_wtime() - copy_start);
  run.max_cell_occupancy = registry_.max_occupancy;
  run.hashed_index = registry_.hashed;
  run.index_bytes = registry_.index_bytes();
  return grid;
}

// The unsorted double loops read their candidates' coordinates at random in the input order:
// from this copy in huge pages (LargeVector) where the scene is past copy_for_random_reads, for
// its std::vector arrays lie in 4 KiB pages and nearly every candidate's reads also missed the
// TLB (the paper scene's unsorted particle loop: T_c 2.97 - 3.08 s -> 2.28 - 2.35 s at one
// thread). The order is the input's: this is no reordering. Counted in T_s, in its reorder part.
void ContactDetector::copy_in_input_order(const Scene& scene, int threads) {
  const std::size_t n = scene.size();
  const bool diameters = scene.has_diameters();
  working_.x.resize(n);
  working_.y.resize(n);
  working_.z.resize(n);
  working_.diameter.resize(diameters ? n : 0);
  double *const x = working_.x.data(), *const y = working_.y.data(), *const z = working_.z.data(),
                *const d = working_.diameter.data();
#pragma omp parallel for schedule(static) num_threads(threads)
  for (std::size_t i = 0; i < n; ++i) {
    x[i] = scene.x[i];
    y[i] = scene.y[i];
    z[i] = scene.z[i];
    if (diameters) d[i] = scene.diameter[i];
  }
}

// Calls f(layout) with the prepared particles in the working order and the given precision.
template <class F>
void ContactDetector::with_layout(const Scene& scene, Precision precision, DetectRun& run, F&& f) {
  struct Source {  // the coordinates in working order
    const double *x, *y, *z, *diameter;
  };
  const Source source =
      working_is_sorted_ || working_is_copy_
          ? Source{working_.x.data(), working_.y.data(), working_.z.data(),
                   working_.diameter.data()}
          : Source{scene.x.data(), scene.y.data(), scene.z.data(), scene.diameter.data()};
  const bool diameters = scene.has_diameters();
  // The double coordinates, for the float test's second test within its rounding band.
  const ExactCoordinates exact{source.x, source.y, source.z, diameters ? source.diameter : nullptr,
                               0.0};
  double extent = 0.0;  // of the float coordinates: the band grows with it
  auto run_with = [&](const auto& coordinates) {
    using Real = std::remove_cvref_t<decltype(*coordinates.x)>;
    if (working_is_sorted_) {
      f(traversal::SortedLayout<Real>{coordinates, registry_.slot_particle.data()}, exact, extent);
    } else {
      f(traversal::UnsortedLayout<Real>{coordinates, registry_.slot_particle.data(),
                                        registry_.particle_slot.data()},
        exact, extent);
    }
  };
  if (precision == Precision::kDouble) {
    run_with(traversal::Coordinates<double>{source.x, source.y, source.z, source.x, source.y,
                                            source.z, diameters ? source.diameter : nullptr});
    return;
  }
  // Single precision, relative to the box's lower corner (absolute coordinates far from the
  // origin would lose most of their float digits). The conversion is part of the setup, as a
  // code keeping float coordinates would do it once when they change.
  const double convert_start = omp_get_wtime();
  const std::size_t n = scene.size();
  const auto& lo = scene.box.lo;
  narrow_x_.resize(n);
  narrow_y_.resize(n);
  narrow_z_.resize(n);
  narrow_d_.resize(diameters ? n : 0);
#pragma omp parallel for schedule(static) num_threads(run.threads) reduction(max : extent)
  for (std::size_t i = 0; i < n; ++i) {
    narrow_x_[i] = static_cast<float>(source.x[i] - lo[0]);
    narrow_y_[i] = static_cast<float>(source.y[i] - lo[1]);
    narrow_z_[i] = static_cast<float>(source.z[i] - lo[2]);
    if (diameters) narrow_d_[i] = static_cast<float>(source.diameter[i]);
    extent = std::max({extent, std::abs(static_cast<double>(narrow_x_[i])),
                       std::abs(static_cast<double>(narrow_y_[i])),
                       std::abs(static_cast<double>(narrow_z_[i]))});
  }
  run.setup_s += omp_get_wtime() - convert_start;
  run_with(traversal::Coordinates<float>{source.x, source.y, source.z, narrow_x_.data(),
                                         narrow_y_.data(), narrow_z_.data(),
                                         diameters ? narrow_d_.data() : nullptr});
}

// SIMD where a home's stencil holds enough candidates on average: 27 cells of the mean
// occupancy a particle sees, itself not counted (uniform at D = 1/200: about 3.5).
bool ContactDetector::tests_on_lanes() const {
  const std::size_t n = registry_.slot_particle.size();
  const double candidates_estimate =
      n == 0 ? 0.0
             : 27.0 * (static_cast<double>(registry_.occupancy_squares) / static_cast<double>(n) -
                       1.0);
  return working_is_sorted_ && simd_enabled() &&
         (simd_forced() || candidates_estimate >= static_cast<double>(pair_ops::kSimdFrom));
}

DetectRun ContactDetector::run(const Scene& scene, const DetectOptions& options) {
  DetectRun run;
  const CellGrid grid = prepare(scene, options, 0.0, run);
  const bool simd = tests_on_lanes();
  const std::uint64_t scalar_below = simd_forced() ? 0 : pair_ops::kSimdFrom;
  with_layout(
      scene, options.variant.precision, run,
      [&](const auto& layout, ExactCoordinates exact, double extent) {
        using Real = typename std::remove_cvref_t<decltype(layout)>::Real;
        const Real diameter = static_cast<Real>(options.diameter);
        // Float: the rounding band for any candidate of the stencil (offsets under two cells).
        exact.reach_sq = options.diameter * options.diameter;
        const auto& width = grid.cell_width();
        const FloatBand band =
            FloatBand::make(extent, 2.0 * std::max({width[0], width[1], width[2]}),
                            layout.d ? scene.max_diameter() : options.diameter, exact.reach_sq);
        if (simd) {
          if (layout.d) {
            detect(grid, layout,
                   SimdContactTest<Real, true>{layout.x, layout.y, layout.z, layout.d, Real(0),
                                               exact, band, scalar_below},
                   options, run);
          } else {
            detect(grid, layout,
                   SimdContactTest<Real, false>{layout.x, layout.y, layout.z, nullptr,
                                                diameter * diameter, exact, band, scalar_below},
                   options, run);
          }
        } else if (layout.d) {
          detect(grid, layout, ContactTest<Real, true>{layout.d, Real(0), exact, band}, options,
                 run);
        } else {
          detect(grid, layout, ContactTest<Real, false>{nullptr, diameter * diameter, exact, band},
                 options, run);
        }
      });
  return run;
}

ContactList ContactDetector::neighbor_list(const Scene& scene, const DetectOptions& options,
                                           double skin) {
  if (!(skin >= 0.0 && skin < 1e300)) {
    throw InputError("skin must be a finite number >= 0 (got " + number_text(skin) + ")");
  }
  DetectOptions full = options;
  full.variant.stencil = Stencil::kFull;
  DetectRun run;
  const CellGrid grid = prepare(scene, full, skin, run);
  with_layout(scene, full.variant.precision, run, [&](const auto& layout, auto&&...) {
    using Layout = std::remove_cvref_t<decltype(layout)>;
    using Real = typename Layout::Real;
    if (layout.d) {
      detect(grid, layout, NeighborTest<Layout, true>{&layout, 0, Real(skin), full.homes}, full,
             run);
    } else {
      const Real reach = static_cast<Real>(options.diameter + skin);
      detect(grid, layout, NeighborTest<Layout, false>{&layout, reach * reach, 0, full.homes}, full,
             run);
    }
  });
  return canonicalize(contacts_, working_to_input(), options.threads);
}

void ContactDetector::release_buffers() {
  std::vector<detail::ThreadOutput>().swap(thread_out_);
  LargeVector<std::uint32_t>().swap(found_count_);
  LargeVector<std::uint32_t>().swap(reverse_count_);
  LargeVector<std::uint64_t>().swap(row_weight_);
  working_ = {};
  narrow_x_ = narrow_y_ = narrow_z_ = narrow_d_ = {};
  registry_.release_scratch();
}

// The same traversal as run(), with an op that counts instead of testing.
LoopWork ContactDetector::iteration_work(const Scene& scene, const DetectOptions& options) {
  DetectRun run;
  const CellGrid grid = prepare(scene, options, 0.0, run);
  const Variant& variant = options.variant;
  const std::size_t iterations = variant.loop == LoopKind::kParticle
                                     ? scene.size()
                                     : traversal::cell_iterations(grid, registry_);
  LoopWork work;
  work.tests.assign(iterations, 0);
  work.homes.assign(iterations, 0);
  work.builds.assign(iterations, 0);
  WorkCountOp op{work};
  // The tiles the contact test would use (its ranges, and so its tests and builds).
  const std::uint32_t tile_homes = tests_on_lanes() ? simd::kBlockHomes : 0;
  // Only the cells are read: double coordinates in the working order, whatever the precision.
  with_layout(scene, Precision::kDouble, run, [&](const auto& layout, auto&&...) {
    traversal::traverse(
        {grid, registry_, variant.loop, variant.stencil, options.homes, options.blocks, tile_homes},
        layout, op);
  });
  if (options.blocks.all()) return work;
  // Loop order: the loop runs over this process's blocks only (k -> blocks.at(k)), so the
  // schedule divides exactly those; the counts were kept by iteration id.
  LoopWork mine;
  const std::uint64_t size = options.blocks.size(iterations);
  mine.tests.resize(size);
  mine.homes.resize(size);
  mine.builds.resize(size);
  for (std::uint64_t k = 0; k < size; ++k) {
    const std::uint64_t i = options.blocks.at(k);
    mine.tests[k] = work.tests[i];
    mine.homes[k] = work.homes[i];
    mine.builds[k] = work.builds[i];
  }
  return mine;
}

}  // namespace contactlab
