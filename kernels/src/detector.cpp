// Contact detection: one traversal skeleton shared by every variant. The variant picks the
// layout (sorted coordinates or indirection through cell lists), the outer loop (cells or
// particles), the stencil (27 cells or own cell + 13 forward) and the OpenMP schedule.
#include "contactlab/kernels/detector.hpp"

#include <omp.h>

#include <algorithm>
#include <atomic>
#include <cstring>

#include "contactlab/kernels/error.hpp"
#include "contactlab/kernels/pair_test.hpp"

namespace contactlab {
namespace {

// Stencil offsets (dx, dy, dz). Index 0 is always the own cell: its search range is special
// (skip oneself with the full stencil, only later slots with the half stencil).
struct StencilOffsets {
  std::array<std::array<int, 3>, 27> offsets{};
  int count = 0;
};

StencilOffsets make_stencil(Stencil stencil) {
  StencilOffsets result;
  result.offsets[result.count++] = {0, 0, 0};
  for (int dz = -1; dz <= 1; ++dz) {
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        if (dx == 0 && dy == 0 && dz == 0) continue;
        // Forward half: (dz, dy, dx) lexicographically after (0, 0, 0). Each unordered pair
        // of distinct neighbour cells is then visited from exactly one of them.
        const bool forward = dz > 0 || (dz == 0 && (dy > 0 || (dy == 0 && dx > 0)));
        if (stencil == Stencil::kFull || forward) result.offsets[result.count++] = {dx, dy, dz};
      }
    }
  }
  return result;
}

struct SlotRange {
  std::uint32_t begin, end;
};

// The occupied cells of a home cell's stencil; ranges[0] is the own cell.
struct NeighbourRanges {
  std::array<SlotRange, 27> ranges{};
  int count = 0;
  std::uint64_t candidates = 0;  // slots in all ranges

  void build(const CellGrid& grid, const CellRegistry& registry, const StencilOffsets& stencil,
             const std::array<int, 3>& home) {
    count = 0;
    candidates = 0;
    for (int o = 0; o < stencil.count; ++o) {
      const auto& d = stencil.offsets[o];
      const int cx = home[0] + d[0], cy = home[1] + d[1], cz = home[2] + d[2];
      if (!grid.in_range(cx, cy, cz)) continue;
      const std::uint32_t key = grid.key(cx, cy, cz);
      const SlotRange range{registry.cell_begin[key], registry.cell_begin[key + 1]};
      if (o != 0 && range.begin == range.end) continue;
      ranges[count++] = range;
      candidates += range.end - range.begin;
    }
  }
};

// Coordinates stored in slot order: working id == slot, no indirection.
struct SortedLayout {
  const double *x, *y, *z, *d;
  const std::uint32_t* particle_slot_unused;
  std::uint32_t particle_at(std::uint32_t slot) const { return slot; }
  std::uint32_t slot_of(std::uint32_t particle) const { return particle; }
};

// Coordinates in input order: cell lists map slots to input ids (the paper's unsorted case).
struct UnsortedLayout {
  const double *x, *y, *z, *d;
  const std::uint32_t* slot_particle;
  const std::uint32_t* particle_slot;
  std::uint32_t particle_at(std::uint32_t slot) const { return slot_particle[slot]; }
  std::uint32_t slot_of(std::uint32_t particle) const { return particle_slot[particle]; }
};

// Tests home particle h (in slot s_h) against the candidate ranges, appending partners.
template <class Layout, bool kHalf, bool kDiameters>
inline void test_home(const Layout& layout, const NeighbourRanges& nb, std::uint32_t h,
                      std::uint32_t s_h, double reach_sq, std::vector<std::uint32_t>& out) {
  const double xi = layout.x[h], yi = layout.y[h], zi = layout.z[h];
  const double di = kDiameters ? layout.d[h] : 0.0;
  auto test_range = [&](std::uint32_t begin, std::uint32_t end) {
    for (std::uint32_t s = begin; s < end; ++s) {
      const std::uint32_t j = layout.particle_at(s);
      const double dx = xi - layout.x[j], dy = yi - layout.y[j], dz = zi - layout.z[j];
      bool touching;
      if constexpr (kDiameters) {
        touching = in_contact(dx, dy, dz, di, layout.d[j]);
      } else {
        touching = in_contact(dx, dy, dz, reach_sq);
      }
      if (touching) out.push_back(j);
    }
  };
  const SlotRange own = nb.ranges[0];
  if constexpr (kHalf) {
    test_range(s_h + 1, own.end);
  } else {
    test_range(own.begin, s_h);
    test_range(s_h + 1, own.end);
  }
  for (int r = 1; r < nb.count; ++r) test_range(nb.ranges[r].begin, nb.ranges[r].end);
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
  const StencilOffsets stencil = make_stencil(variant.stencil);
  const double reach_sq = options.diameter * options.diameter;

  if (thread_partners_.size() < static_cast<std::size_t>(threads)) thread_partners_.resize(threads);
  found_count_.resize(n);
  found_thread_.resize(n);
  found_offset_.resize(n);
  if (half) reverse_count_.resize(n);
  contacts_.offsets.resize(std::size_t{n} + 1);
  run.thread_busy_s.assign(threads, 0.0);
  std::vector<std::uint64_t> thread_tests(threads, 0);

  omp_set_schedule(to_omp(variant.schedule.kind), variant.schedule.chunk);
  if (options.observer) options.observer->region_begin(threads);
  const double start = omp_get_wtime();

#pragma omp parallel num_threads(threads)
  {
    const int tid = omp_get_thread_num();
    std::vector<std::uint32_t>& out = thread_partners_[tid];
    out.clear();
    std::uint64_t tests = 0;
    NeighbourRanges nb;

    auto visit = [&](auto half_tag, auto diameters_tag, std::uint32_t h, std::uint32_t s_h) {
      const std::uint64_t before = out.size();
      test_home<Layout, decltype(half_tag)::value, decltype(diameters_tag)::value>(
          layout, nb, h, s_h, reach_sq, out);
      found_count_[h] = static_cast<std::uint32_t>(out.size() - before);
      found_thread_[h] = static_cast<std::uint16_t>(tid);
      found_offset_[h] = before;
      // Own cell: with the half stencil only later slots; with the full one all but oneself.
      const SlotRange own = nb.ranges[0];
      tests += nb.candidates - (decltype(half_tag)::value ? (s_h + 1 - own.begin) : 1);
    };

    if (options.observer) options.observer->thread_begin(tid);
    const double loop_start = omp_get_wtime();
    dispatch_bool(half, [&](auto half_tag) {
      dispatch_bool(diameters, [&](auto diameters_tag) {
        if (variant.loop == LoopKind::kParticle) {
          std::uint32_t cached_key = UINT32_MAX;
#pragma omp for schedule(runtime) nowait
          for (std::uint32_t h = 0; h < n; ++h) {
            const auto home = grid.coords_of(layout.x[h], layout.y[h], layout.z[h]);
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
            nb.build(grid, registry_, stencil,
                     grid.coords_of(layout.x[first], layout.y[first], layout.z[first]));
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

    // Assemble the rows. Each particle's own finds sit in one thread's buffer; with the half
    // stencil each find (h, j) also belongs in j's row, placed through per-row atomic cursors.
    if (half) {
#pragma omp for schedule(static)
      for (std::uint32_t i = 0; i < n; ++i) reverse_count_[i] = 0;
      for (const std::uint32_t j : out) {
        std::atomic_ref<std::uint32_t>(reverse_count_[j]).fetch_add(1, std::memory_order_relaxed);
      }
#pragma omp barrier
    }
#pragma omp single
    {
      std::uint64_t total = 0;
      contacts_.offsets[0] = 0;
      for (std::uint32_t i = 0; i < n; ++i) {
        total += found_count_[i] + (half ? reverse_count_[i] : 0);
        contacts_.offsets[i + 1] = total;
        if (half) reverse_count_[i] = found_count_[i];  // becomes the row's fill cursor
      }
      contacts_.partners.resize(total);
    }
    std::uint32_t* partners = contacts_.partners.data();
#pragma omp for schedule(static)
    for (std::uint32_t h = 0; h < n; ++h) {
      const std::uint32_t* found = thread_partners_[found_thread_[h]].data() + found_offset_[h];
      const std::uint32_t count = found_count_[h];
      if (count == 0) continue;
      std::memcpy(partners + contacts_.offsets[h], found, count * sizeof(std::uint32_t));
      if (half) {
        for (std::uint32_t k = 0; k < count; ++k) {
          const std::uint32_t j = found[k];
          const std::uint32_t at = std::atomic_ref<std::uint32_t>(reverse_count_[j])
                                       .fetch_add(1, std::memory_order_relaxed);
          partners[contacts_.offsets[j] + at] = h;
        }
      }
    }
  }
  run.detect_s = omp_get_wtime() - start;
  if (options.observer) options.observer->region_end();
  run.candidate_tests = 0;
  for (const auto t : thread_tests) run.candidate_tests += t;
  run.contact_pairs = contacts_.pair_count();
}

DetectRun ContactDetector::run(const Scene& scene, const DetectOptions& options) {
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

  DetectRun run;
  run.threads = options.threads > 0 ? options.threads : omp_get_max_threads();
  const Order order = options.variant.order;
  const CellGrid grid(scene.box, diameters ? scene.max_diameter() : options.diameter,
                      order == Order::kMorton ? CellNumbering::kMorton : CellNumbering::kLinear);
  run.grid_dims = grid.dims();

  const double setup_start = omp_get_wtime();
  registry_.assign(grid, scene);
  working_is_sorted_ = order != Order::kUnsorted;
  const std::size_t n = scene.size();
  if (working_is_sorted_) {
    sorted_x_.resize(n);
    sorted_y_.resize(n);
    sorted_z_.resize(n);
    sorted_d_.resize(diameters ? n : 0);
    const std::uint32_t* slot_particle = registry_.slot_particle.data();
#pragma omp parallel for schedule(static) num_threads(run.threads)
    for (std::size_t s = 0; s < n; ++s) {
      const std::uint32_t i = slot_particle[s];
      sorted_x_[s] = scene.x[i];
      sorted_y_[s] = scene.y[i];
      sorted_z_[s] = scene.z[i];
      if (diameters) sorted_d_[s] = scene.diameter[i];
    }
  }
  run.setup_s = omp_get_wtime() - setup_start;
  run.max_cell_occupancy = registry_.max_occupancy;

  if (working_is_sorted_) {
    const SortedLayout layout{sorted_x_.data(), sorted_y_.data(), sorted_z_.data(),
                              diameters ? sorted_d_.data() : nullptr, nullptr};
    detect(grid, layout, options, run);
  } else {
    const UnsortedLayout layout{scene.x.data(),
                                scene.y.data(),
                                scene.z.data(),
                                diameters ? scene.diameter.data() : nullptr,
                                registry_.slot_particle.data(),
                                registry_.particle_slot.data()};
    detect(grid, layout, options, run);
  }
  return run;
}

}  // namespace contactlab
