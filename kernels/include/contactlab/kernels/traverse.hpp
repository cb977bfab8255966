// The cell-stencil traversal, written once for every use (contact lists, per-iteration work
// counts, neighbour lists): what is done with a candidate pair is the caller's PairOp.
//
// traverse(spec, layout, op) runs the variant's loop (cells or particles) over the home
// particles with the variant's stencil (27 cells or own cell + 13 forward) and calls, per home,
//
//   auto sink = op.begin_home(home);   // home: particle, slot, loop iteration, tests, built
//   sink(j, dx, dy, dz);               // per candidate j, dx = x_home - x_j (if Op::kTestsPairs)
//   op.end_home(home, sink);
//
// or, where the op has visit_block (the SIMD contact test of the sorted layouts, whose slots are
// working ids), one call per block of up to Op::kBlockHomes homes of one cell, in visiting
// order, with the cell's stencil as slot ranges: op.visit_block(homes, count, ranges, half).
//
// The sink is a value local to the loop, so the per-candidate state of an op (the next free
// place of a branchless append, a count) stays in registers. Ops with kTestsPairs = false see
// only the homes (with their test counts) and no candidate is read.
//
// The loop is an orphaned `omp for schedule(runtime) nowait`: called inside a parallel region
// each thread visits its share of the homes with its own op; called outside one, it is serial.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <type_traits>

#include "contactlab/kernels/balanced_blocks.hpp"
#include "contactlab/kernels/cell_grid.hpp"
#include "contactlab/kernels/cell_index.hpp"
#include "contactlab/kernels/detector.hpp"
#include "contactlab/kernels/slot_range.hpp"
#include "contactlab/kernels/stencil.hpp"
#include "contactlab/kernels/variant.hpp"

namespace contactlab::traversal {

// Where the traversal reads particles. `cell_x/y/z` are the double coordinates the particles
// were registered with (a home particle's cell must be found exactly as registration did);
// `x/y/z/d` are the coordinates the pair ops read, in the variant's precision T (d is null
// without per-particle diameters).
template <class T>
struct Coordinates {
  const double *cell_x, *cell_y, *cell_z;
  const T *x, *y, *z, *d;
};

// Coordinates stored in slot order: working id == slot, no indirection.
template <class T>
struct SortedLayout : Coordinates<T> {
  using Real = T;
  static constexpr bool kIdsAreSlots = true;
  const std::uint32_t* slot_particle;  // slot -> input row
  std::uint32_t particle_at(std::uint32_t slot) const { return slot; }
  std::uint32_t slot_of(std::uint32_t particle) const { return particle; }
  std::uint32_t input_of(std::uint32_t particle) const { return slot_particle[particle]; }
};

// Coordinates in input order: cell lists map slots to input ids (the paper's unsorted case).
template <class T>
struct UnsortedLayout : Coordinates<T> {
  using Real = T;
  static constexpr bool kIdsAreSlots = false;
  const std::uint32_t* slot_particle;
  const std::uint32_t* particle_slot;
  std::uint32_t particle_at(std::uint32_t slot) const { return slot_particle[slot]; }
  std::uint32_t slot_of(std::uint32_t particle) const { return particle_slot[particle]; }
  std::uint32_t input_of(std::uint32_t particle) const { return particle; }
};

// What to traverse: the registered grid, the variant's loop and stencil, and the homes.
struct Spec {
  const CellGrid& grid;
  const CellRegistry& registry;
  LoopKind loop;
  Stencil stencil;
  HomeRange homes;      // input rows; every registered particle is a candidate
  HomeBlocks blocks{};  // the loop iterations this process visits (all by default)
  // Particle loop, linear numbering: neighbouring occupied cells along x holding at most this
  // many particles together are one tile (find_tile), whose homes share one range build with
  // rows a cell longer per cell joined, and are visited as one block (0: each cell alone).
  std::uint32_t tile_homes = 0;
  // The balanced schedule: each thread visits the block of equal pair tests (plus kHomeTests a
  // home) this gives it, not the omp for's share; null for the OpenMP schedules.
  BalancedBlocks* balanced = nullptr;
};

// Whether the traversal of `spec` makes tiles: the particle loop (cells visited in slot order)
// with the linear numbering (a row's cells are consecutive keys), where the op asked for them.
inline bool uses_tiles(const Spec& spec) {
  return spec.tile_homes > 0 && spec.loop == LoopKind::kParticle &&
         spec.grid.numbering() == CellNumbering::kLinear;
}

// The most cells along x a tile spans (a power of two, see find_tile). On the paper's scene,
// tiles of up to eight cells and four particles cut the range builds from 601,000 to 394,000
// (docs/architecture.md).
inline constexpr int kTileCells = 8;

// How far past a stencil row's end its coordinates are prefetched at each range build.
inline constexpr int kRowBytesAhead = 128;

// The tile holding the occupied cell at x (key `key`) in its row along x: cells first..last and
// their slots. The aligned group of kTileCells cells holding x is one tile if it holds at most
// `limit` particles; else its half holding x, and so on down to the cell alone. Tiles thus
// depend on the occupancy only, not on where a thread's share of the loop begins (the tests made
// do not depend on the schedule), and each level costs one slot range: a greedy scan from the
// group's start, cell by cell, ran 8 % slower than this on the paper's scene (its branches).
struct Tile {
  int first, last;
  SlotRange slots;
};

template <class Index>
Tile find_tile(const Index& index, std::uint64_t key, int x, int cells_along_x,
               std::uint32_t limit) {
  const SlotRange own = index.cell_slots(key);
  if (own.end - own.begin <= limit) {
    const std::uint64_t row_key = key - static_cast<std::uint64_t>(x);  // of cell 0 of the row
    for (int size = kTileCells; size > 1; size /= 2) {
      const int first = x - x % size;
      const int last = std::min(first + size, cells_along_x) - 1;
      const SlotRange group = index.cell_slots_of(row_key + static_cast<std::uint64_t>(first),
                                                  row_key + static_cast<std::uint64_t>(last));
      if (group.end - group.begin <= limit) return {first, last, group};
    }
  }
  return {x, x, own};
}

// One visit of a home particle, as an op sees it.
struct Home {
  std::uint32_t particle;   // working id
  std::uint32_t slot;       // its slot in the cell lists
  std::uint64_t iteration;  // of the parallel loop: the cell (its key with the dense index, its
                            // place among the occupied cells with the hashed one), or the particle
  std::uint64_t tests;      // candidates it is tested against (the home itself excluded)
  bool built;               // whether the stencil's ranges were built for it
};

// Calls sink(j, dx, dy, dz) for every candidate of the home in slot s_h, in slot order
// within each stencil range (the order of the partners in a contact row).
template <bool kHalf, class Layout, class Sink>
inline void for_each_candidate(const Layout& layout, const NeighbourRanges& nb, std::uint32_t h,
                               std::uint32_t s_h, Sink& sink) {
  using Real = typename Layout::Real;
  const Real xi = layout.x[h], yi = layout.y[h], zi = layout.z[h];
  auto visit_range = [&](std::uint32_t begin, std::uint32_t end) {
    for (std::uint32_t s = begin; s < end; ++s) {
      const std::uint32_t j = layout.particle_at(s);
      sink(j, xi - layout.x[j], yi - layout.y[j], zi - layout.z[j]);
    }
  };
  for (int r = 0; r < nb.count; ++r) {
    const SlotRange range = nb.ranges[r];
    if (r != nb.own) {
      visit_range(range.begin, range.end);
    } else if constexpr (kHalf) {
      // The range starts at the home cell: only its later slots and the cells after it.
      visit_range(s_h + 1, range.end);
    } else {
      visit_range(range.begin, s_h);
      visit_range(s_h + 1, range.end);
    }
  }
}

// How many homes of one cell an op takes at once: Op::kBlockHomes where it has
// visit_block(homes, count, ranges, half), else 1 (begin_home / end_home per home).
template <class Op>
constexpr int block_homes() {
  if constexpr (requires { Op::kBlockHomes; }) {
    return Op::kBlockHomes;
  } else {
    return 1;
  }
}

template <bool kHalf, class Index, class Layout, class Op>
void traverse_with(const Spec& spec, const Index& index, const Layout& layout, Op& op) {
  const CellGrid& grid = spec.grid;
  const std::uint32_t n = static_cast<std::uint32_t>(spec.registry.slot_particle.size());
  const StencilRows stencil = make_stencil(spec.stencil).with_key_steps(grid.dims());
  const bool all_owned = spec.homes.covers(n);
  NeighbourRanges nb;
  // Homes of one cell waiting to be visited together (ops with kBlockHomes > 1): they share the
  // ranges in `nb`, so the block is visited before `nb` is built for another cell.
  constexpr int kBlock = block_homes<Op>();
  const bool tiles = uses_tiles(spec);
  std::array<Home, kBlock> block;
  int waiting = 0;
  // After each build, the stencil rows' coordinates a little past their ends are fetched: the
  // next tiles along x read there, and the rows of the next y and z read there for the first
  // time (nine rows of three arrays are more streams than the hardware's prefetchers follow).
  auto prefetch_rows_ahead = [&] {
    if constexpr (Op::kTestsPairs && Layout::kIdsAreSlots) {
      for (int r = 0; r < nb.count; ++r) {
        const std::uint32_t end = nb.ranges[r].end;
        __builtin_prefetch(reinterpret_cast<const char*>(layout.x + end) + kRowBytesAhead);
        __builtin_prefetch(reinterpret_cast<const char*>(layout.y + end) + kRowBytesAhead);
        __builtin_prefetch(reinterpret_cast<const char*>(layout.z + end) + kRowBytesAhead);
      }
    }
  };
  auto flush = [&] {
    if constexpr (kBlock > 1) {
      if (waiting > 0) op.visit_block(block.data(), waiting, nb, kHalf);
      waiting = 0;
    }
  };
  auto visit = [&](std::uint32_t h, std::uint32_t s_h, std::uint64_t iteration, bool built) {
    const Home home{h, s_h, iteration, nb.tests_from(s_h, kHalf), built};
    if constexpr (kBlock > 1) {
      if (waiting == kBlock) flush();
      block[waiting++] = home;
    } else {
      auto sink = op.begin_home(home);
      if constexpr (Op::kTestsPairs) for_each_candidate<kHalf>(layout, nb, h, s_h, sink);
      op.end_home(home, sink);
    }
  };
  // The loop iteration -> particle (or cell) map is chosen outside the loop, so the
  // single-process loop carries no block arithmetic (most cell-loop iterations are empty).
  auto loops = [&](auto iteration_at) {
    if (spec.loop == LoopKind::kParticle) {
      std::uint64_t cached_key = UINT64_MAX;  // ranges are reused while the cell stays the same
      // The cached cell's slots: a home among them is in that cell, and its cell coordinates
      // (three multiplications and floors) need not be found again.
      SlotRange cached_cell{0, 0};
      // Only this process's iterations enter the loop, so its threads' schedule divides them.
      const std::uint64_t iterations = spec.blocks.size(n);
      auto visit_particle = [&](std::uint64_t k) __attribute__((always_inline)) {
        const auto h = static_cast<std::uint32_t>(iteration_at(k));
        if (!all_owned && !spec.homes.contains(layout.input_of(h))) return;
        const std::uint32_t s_h = layout.slot_of(h);
        bool built = false;
        if (s_h < cached_cell.begin || s_h >= cached_cell.end) {
          const auto home = grid.coords_of(layout.cell_x[h], layout.cell_y[h], layout.cell_z[h]);
          const std::uint64_t key = index.key(grid, home[0], home[1], home[2]);
          built = key != cached_key;
          if (built) {
            flush();
            cached_key = key;
            if (tiles) {
              // The tile's rows reach from its first cell's x - 1 to its last one's x + 1. The
              // candidates this adds to a home's are at least two cells from it along x: never a
              // contact, so the contacts and their order are those of the cell alone, and with
              // the half stencil no pair is found from both sides.
              const Tile tile = find_tile(index, key, home[0], grid.dims()[0], spec.tile_homes);
              cached_cell = tile.slots;
              nb.build(grid, index, stencil, {tile.first, home[1], home[2]},
                       tile.last - tile.first + 1);
            } else {
              cached_cell = index.cell_slots(key);
              nb.build(grid, index, stencil, home);
            }
            prefetch_rows_ahead();
          }
        }
        visit(h, s_h, h, built);
      };
      // The balanced branch out of line: inside the OpenMP branch's function its weighing cost
      // the block schedule's cell loop 3.6 % at one thread (code and registers, not work).
      auto balanced_loop = [&]() __attribute__((noinline)) {
        // A home weighs its pair tests (its cell's stencil, built once per cell as the loop
        // does) plus kHomeTests.
        NeighbourRanges weighing;
        SlotRange weighed{0, 0};  // the cell `weighing` was built for
        const IterationBlock mine = spec.balanced->block(iterations, [&](std::uint64_t k) {
          const auto h = static_cast<std::uint32_t>(iteration_at(k));
          const std::uint32_t s_h = layout.slot_of(h);
          if (s_h < weighed.begin || s_h >= weighed.end) {
            const auto home = grid.coords_of(layout.cell_x[h], layout.cell_y[h], layout.cell_z[h]);
            weighed = index.cell_slots(index.key(grid, home[0], home[1], home[2]));
            weighing.build(grid, index, stencil, home);
          }
          return weighing.tests_from(s_h, kHalf) + kHomeTests;
        });
        for (std::uint64_t k = mine.begin; k < mine.end; ++k) visit_particle(k);
      };
      if (spec.balanced) {
        balanced_loop();
      } else {
#pragma omp for schedule(runtime) nowait
        for (std::uint64_t k = 0; k < iterations; ++k) visit_particle(k);
      }
      flush();
    } else {
      // One iteration per cell key (dense index) or per occupied cell (hashed index).
      const std::uint64_t iterations = spec.blocks.size(index.cell_iterations());
      auto visit_cell = [&](std::uint64_t k) __attribute__((always_inline)) {
        const std::uint64_t cell = iteration_at(k);
        const SlotRange slots = index.iteration_slots(cell);
        if (slots.begin == slots.end) return;
        const std::uint32_t first = layout.particle_at(slots.begin);
        flush();
        nb.build(grid, index, stencil,
                 grid.coords_of(layout.cell_x[first], layout.cell_y[first], layout.cell_z[first]));
        prefetch_rows_ahead();
        bool built = true;  // reported with the cell's first home
        for (std::uint32_t s = slots.begin; s < slots.end; ++s) {
          const std::uint32_t h = layout.particle_at(s);
          if (!all_owned && !spec.homes.contains(layout.input_of(h))) continue;
          visit(h, s, cell, built);
          built = false;
        }
      };
      auto balanced_loop = [&]() __attribute__((noinline)) {
        // A cell weighs its homes' pair tests plus kHomeTests each; an empty one (a key of
        // the dense index) 1.
        NeighbourRanges weighing;
        const IterationBlock mine = spec.balanced->block(iterations, [&](std::uint64_t k) {
          const SlotRange slots = index.iteration_slots(iteration_at(k));
          const std::uint64_t homes = slots.end - slots.begin;
          if (homes == 0) return std::uint64_t{1};
          const std::uint32_t first = layout.particle_at(slots.begin);
          weighing.build(
              grid, index, stencil,
              grid.coords_of(layout.cell_x[first], layout.cell_y[first], layout.cell_z[first]));
          // Full: every candidate but itself; half: the own cell's later homes, 0 .. homes - 1.
          const std::uint64_t tests = kHalf ? homes * weighing.candidates - homes * (homes + 1) / 2
                                            : homes * (weighing.candidates - 1);
          return 1 + tests + homes * kHomeTests;
        });
        for (std::uint64_t k = mine.begin; k < mine.end; ++k) visit_cell(k);
      };
      if (spec.balanced) {
        balanced_loop();
      } else {
#pragma omp for schedule(runtime) nowait
        for (std::uint64_t k = 0; k < iterations; ++k) visit_cell(k);
      }
      flush();
    }
  };
  if (spec.blocks.all()) {
    loops([](std::uint64_t k) { return k; });
  } else {
    loops([&](std::uint64_t k) { return spec.blocks.at(k); });
  }
}

// The iterations of the cell loop: one per key of a dense registration, one per occupied cell
// of a hashed one.
inline std::uint64_t cell_iterations(const CellGrid& grid, const CellRegistry& registry) {
  return registry.hashed ? registry.occupied.size() : grid.key_count();
}

// The traversal, with the stencil and the cell index chosen at compile time.
template <class Layout, class Op>
void traverse(const Spec& spec, const Layout& layout, Op& op) {
  auto with_index = [&](const auto& index) {
    if (spec.stencil == Stencil::kHalf) {
      traverse_with<true>(spec, index, layout, op);
    } else {
      traverse_with<false>(spec, index, layout, op);
    }
  };
  if (spec.registry.hashed) {
    // Homes come in key order in the cell loop and in the particle loop over sorted particles.
    const bool in_key_order = spec.loop == LoopKind::kCell || Layout::kIdsAreSlots;
    with_index(HashedCellIndex{&spec.registry.occupied, in_key_order});
  } else {
    with_index(DenseCellIndex{spec.registry.cell_begin.data(), spec.grid.key_count()});
  }
}

}  // namespace contactlab::traversal
