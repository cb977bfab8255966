// Cell-grid contact detection in every variant of contactlab::Variant.
//
// One run = setup (register particles in cells; for sorted orders also permute coordinates
// into cell order: the paper's T_s) + detection (the pair tests and the contact lists: T_c).
// Buffers are kept between runs, so repetitions time the work and not the allocator.
//
// Threading: run() uses OpenMP with the variant's schedule (applied through
// schedule(runtime)); results do not depend on the thread count or schedule.
#pragma once

#include <algorithm>
#include <array>
#include <atomic>
#include <cstdint>
#include <span>
#include <vector>

#include "contactlab/kernels/balanced_blocks.hpp"
#include "contactlab/kernels/cell_grid.hpp"
#include "contactlab/kernels/contact_list.hpp"
#include "contactlab/kernels/large_vector.hpp"
#include "contactlab/kernels/partner_buffer.hpp"
#include "contactlab/kernels/scene.hpp"
#include "contactlab/kernels/variant.hpp"

namespace contactlab {

namespace detail {

// What one thread of the detection loop writes: its partners and the homes it visited, on
// cache lines of its own. (Side by side, the threads' size fields shared a line, and every
// home's append moved it between cores: two threads ran the traversal no faster than one.)
// Every buffer grows with what this thread writes, none with the particle count: P threads
// hold N homes and C finds between them, whatever P is (room for every home in each thread's
// list was N x P entries of address space, 1 GB at 256 threads on the paper's scene).
struct alignas(64) ThreadOutput {
  PartnerBuffer partners;
  PartnerBuffer homes;                    // in visiting order
  LargeVector<std::uint32_t> block_rows;  // rows of a block's later homes, before they move
  // Half stencil: the reverse entries this thread found for rows another thread assembles,
  // as (row, partner) pairs in finding order, then grouped by the assembling thread (group t
  // starts at pair spill_begin[t]).
  PartnerBuffer spills;
  LargeVector<std::uint32_t> spills_by_row_block;
  std::vector<std::uint64_t> spill_begin;
  // Half stencil, rows following homes: the reverse entries for this thread's rows that it took
  // from the previous thread's finds itself, as (row, partner) pairs in that thread's finding
  // order (that thread passes it none).
  PartnerBuffer taken;
};

}  // namespace detail

// Hooks around the detection loop, for measurement: thread hooks run on each OpenMP thread
// inside the parallel region (PAPI per-thread event sets); region hooks run on the calling
// thread just outside it (callgrind's collection toggle).
class DetectionObserver {
 public:
  virtual ~DetectionObserver() = default;
  virtual void region_begin(int /*threads*/) {}
  virtual void thread_begin(int /*thread*/) {}
  virtual void thread_end(int /*thread*/) {}
  virtual void region_end() {}
};

// Whether thread 0 of a detection writes its rows in place, into the contact list's storage
// kept from the last run, so that after the loop only the other threads' rows are copied: with
// the full stencil (no reverse entries between rows), homes visited in row order (the particle
// loop, or the cell loop over sorted particles) and thread 0 holding the loop's first
// iterations (one thread, or a static schedule without a chunk size).
bool writes_first_rows_in_place(const Variant& variant, int threads);
// The share of the output entries the assembly copies after the loop: 1 - 1/threads where
// thread 0 writes in place, else 1 (the tuner prices the output per copied entry).
double copied_output_share(const Variant& variant, int threads);
// Whether the half stencil's threads pass their reverse entries on to the threads that own the
// rows: where a thread's homes are not one run of rows back to back with the others' (chunks, a
// dynamic or guided deal, unsorted particles; detector_rows.cpp, choose_row_blocks), rows are
// split by weight and (P - 1) / P of a thread's reverse entries go to other threads. Never with
// the full stencil (no reverse entries) or one thread.
bool passes_reverse_entries_on(const Variant& variant, int threads);

// The one meaning of "threads = 0" everywhere (detect, sweep, tune, --variant auto and the
// tuning cache's keys): OpenMP's default team size, omp_get_max_threads(), which follows
// OMP_NUM_THREADS. Positive counts are returned as they are.
int resolve_threads(int requested);

// The owned particles, input rows [first, last): the traversal's only homes. The others
// (ghosts: copies of a neighbouring domain's particles) sit in the grid and are tested as
// partners of owned homes, never as homes. So with the full stencil the row of an owned
// particle lists all its contacts, ghosts included, and a ghost's row is empty. The half
// stencil finds a pair only from the particle it makes the home (the one whose cell comes
// first in (z, y, x) order, or the earlier slot of a shared cell), so it finds every pair of
// two owned particles (in both rows) but only the owned-ghost pairs whose home is owned.
struct HomeRange {
  std::uint32_t first = 0;
  std::uint32_t last = UINT32_MAX;  // past the particle count = up to the last particle
  bool contains(std::uint32_t i) const { return i >= first && i < last; }
  bool covers(std::uint32_t n) const { return first == 0 && last >= n; }
};

// The detection loop's iterations one process visits when several share the loop (the paper's
// replicated MPI): blocks of `block` consecutive iterations (working ids for the particle loop,
// i.e. reordered particles with the sorted orders; cell keys for the cell loop) dealt
// round-robin to `count` processes, this one being `index`. block = 0: every iteration. The
// threads of the process share its iterations with the variant's schedule.
struct HomeBlocks {
  std::uint32_t block = 0;
  std::uint32_t count = 1;
  std::uint32_t index = 0;
  bool all() const { return block == 0 || count <= 1; }
  // How many of the iterations [0, total) are this process's.
  std::uint64_t size(std::uint64_t total) const {
    if (all()) return total;
    const std::uint64_t round = std::uint64_t{block} * count;
    const std::uint64_t full = total / round;
    const std::uint64_t rest = total - full * round;
    const std::uint64_t start = std::uint64_t{index} * block;
    const std::uint64_t tail = rest > start ? std::min<std::uint64_t>(rest - start, block) : 0;
    return full * block + tail;
  }
  // The k-th of them.
  std::uint64_t at(std::uint64_t k) const {
    if (all()) return k;
    return (k / block) * block * count + std::uint64_t{index} * block + k % block;
  }
};

struct DetectOptions {
  Variant variant;
  // Contact diameter D for scenes without per-particle diameters; ignored otherwise.
  double diameter = 0.0;
  int threads = 0;  // 0 = resolve_threads(0)
  DetectionObserver* observer = nullptr;
  HomeRange homes{};    // default: every particle is owned
  HomeBlocks blocks{};  // default: every iteration of the loop is this process's
  // Cells at least this wide [m] (0: the largest diameter or D, plus skin): processes that hold
  // parts of one scene build the grid one process would.
  double min_cell_width = 0.0;
};

struct DetectRun {
  double setup_s = 0.0;  // T_s: registration and reordering
  // Of T_s: the keys, the sort and the cell index; the reordering (unsorted: the inverse map).
  // Single precision's conversion of the coordinates is the rest.
  double registration_s = 0.0, reorder_s = 0.0;
  double detect_s = 0.0;  // T_c: pair tests and contact lists
  double total_s() const { return setup_s + detect_s; }
  std::vector<double> thread_busy_s;  // each thread's time inside the detection loop
  double weigh_s = 0.0;  // of the loop: the balanced schedule's weighing (0 for other schedules)
  // Pair tests made (each pair twice with the full stencil): the stencil's candidates, and with
  // tiles those of the tiles' longer rows too.
  std::uint64_t candidate_tests = 0;
  std::vector<std::uint64_t> thread_tests;  // each thread's share of them: the loop's balance
  std::vector<std::uint64_t> thread_homes;  // each thread's homes visited
  bool tiled = false;  // sparse cells shared their ranges as tiles (traverse.hpp: find_tile)
  std::uint64_t contact_pairs = 0;
  std::uint32_t max_cell_occupancy = 0;
  std::array<int, 3> grid_dims{};
  bool hashed_index = false;    // the cells were indexed by a hash table over the occupied ones
  std::size_t index_bytes = 0;  // memory of the cell index (dense table, or hashed cells)
  int threads = 0;
};

// The work of each iteration of a detection loop, in loop order (one entry per iteration: per
// particle, or per cell key with the dense index and per occupied cell with the hashed one).
struct LoopWork {
  std::vector<std::uint32_t> tests;  // pair tests
  std::vector<std::uint32_t> homes;  // home particles visited: cell loop, the occupancy; else 1
  // 1 where the iteration builds the stencil's neighbour ranges when its thread ran the
  // previous iteration too: cell loop, every occupied cell; particle loop, a particle whose
  // cell differs from the previous particle's (ranges are reused within a cell).
  std::vector<std::uint8_t> builds;
};

class ContactDetector {
 public:
  // Throws InputError for D <= 0 (without per-particle diameters) or an invalid schedule.
  DetectRun run(const Scene& scene, const DetectOptions& options);

  // What each iteration of the variant's parallel loop (a particle, or a cell with all its
  // particles) will do, in loop order: the exact work a schedule distributes among threads,
  // known from the cell occupancy before any pair is tested. The tuner's zero-run model reads
  // it. Costs one registration and a pass over the stencils. With HomeBlocks, the process's
  // iterations only (the k-th entry is iteration blocks.at(k)), as its loop runs them; with a
  // HomeRange, every iteration, those without an owned home counting none.
  LoopWork iteration_work(const Scene& scene, const DetectOptions& options);

  // Half neighbour list for DEM: every pair within r_i + r_j + skin (D + skin without
  // per-particle diameters) of which at least one particle is owned (options.homes), stored
  // once: in the row of the smaller input row, or of the owned one where the other is a
  // ghost. Rows in input ids, ascending (canonical); ghost rows are empty. The test is the
  // contact test of pair_test.hpp with every diameter (or D) widened by skin, in the variant's
  // precision, and the grid is built for the largest reach. Uses the variant's loop, order,
  // schedule and precision; always the full stencil (the half one would miss owned-ghost
  // pairs, see HomeRange). Replaces contacts(). Throws InputError for skin < 0.
  ContactList neighbor_list(const Scene& scene, const DetectOptions& options, double skin);

  // Frees the buffers kept between runs for speed (per-thread partner lists and bookkeeping,
  // the reordered and single-precision copies, the registration's sort buffers and staged
  // records), keeping contacts() and working_to_input():
  // for a caller that next needs the memory (the MPI output). The next run reallocates them.
  void release_buffers();

  // What the buffers kept between runs hold after the last run, in bytes: their entries, not
  // their capacity (the per-thread buffers are address space, touched only as far as written).
  // `spill_bytes` is the half stencil's reverse entries passed between threads: at most 16
  // bytes a contact pair, whatever the thread count; all else is the same at any thread count
  // but for vectors of a few entries per thread.
  struct BufferBytes {
    std::size_t total = 0;
    std::size_t spill_bytes = 0;
  };
  BufferBytes buffer_bytes() const;

  // Contacts of the last run in working ids (see working_to_input()).
  const ContactList& contacts() const { return contacts_; }
  // Working id -> input row; empty when the working order is the input order.
  std::span<const std::uint32_t> working_to_input() const {
    return working_is_sorted_ ? std::span<const std::uint32_t>(registry_.slot_particle)
                              : std::span<const std::uint32_t>();
  }
  // The last run's contacts in input ids with rows sorted: comparable across variants.
  ContactList canonical_contacts() const { return canonicalize(contacts_, working_to_input()); }

 private:
  CellGrid prepare(const Scene& scene, const DetectOptions& options, double skin, DetectRun& run);
  template <class F>
  void with_layout(const Scene& scene, Precision precision, DetectRun& run, F&& f);
  template <class Layout, class PairTest>
  void detect(const CellGrid& grid, const Layout& layout, const PairTest& test,
              const DetectOptions& options, DetectRun& run);
  // Whether the prepared particles' contact test runs on SIMD lanes (in blocks of homes, with
  // tiles of sparse cells): run() and iteration_work() decide alike.
  bool tests_on_lanes() const;
  // The CSR rows after the traversal (src/detector_rows.cpp), called by every thread of the
  // detection region.
  void assemble_rows(int tid, int threads, bool half, bool rows_in_blocks);
  void assemble_half_rows(int tid, int threads);
  void take_from_previous(int tid, std::uint32_t lo, std::uint32_t hi);
  bool choose_row_blocks(int tid, int threads);
  void finish_offsets(int tid, int threads, std::uint32_t first, std::uint32_t last,
                      std::uint64_t rows_sum);
  void copy_row_blocks(int tid, int threads);
  void copy_in_input_order(const Scene& scene, int threads);

  std::vector<std::uint64_t> range_sums_;  // assemble_rows: each thread's rows, summed
  BalancedBlocks balanced_blocks_;         // the balanced schedule's blocks (traverse.hpp)
  CellRegistry registry_;
  // The coordinates in working order: slot order (sorted orders), or the input's copied into
  // huge pages (unsorted double: copy_in_input_order).
  SortedCoordinates working_;
  LargeVector<float> narrow_x_, narrow_y_, narrow_z_, narrow_d_;  // single-precision copies
  bool working_is_sorted_ = false;  // working ids are slots (sorted orders) or input rows
  bool working_is_copy_ = false;    // unsorted: working_ holds the input order's copy
  ContactList contacts_;
  // Per-thread partner buffers and per-particle bookkeeping, kept between runs.
  std::vector<detail::ThreadOutput> thread_out_;
  LargeVector<std::uint32_t> found_count_;  // own finds per particle
  // Half stencil: the reverse entries of each row, then where the next one goes in it. Thread t
  // assembles rows [row_block_[t], row_block_[t + 1]); home_run_ holds each thread's first home
  // and home count (choose_row_blocks), row_weight_ the rows' weights summed per kWeightRows.
  LargeVector<std::uint32_t> reverse_count_;
  std::vector<std::uint32_t> row_block_;
  std::vector<std::uint64_t> home_run_;
  // Where each thread's finds stop being all for its own rows (kOwnUntilUnknown until it knows):
  // the next thread takes its reverse entries from there on (assemble_half_rows).
  static constexpr std::uint64_t kOwnUntilUnknown = UINT64_MAX;
  std::vector<std::atomic<std::uint64_t>> own_until_;
  LargeVector<std::uint64_t> row_weight_;
};

}  // namespace contactlab
