// Spatial decomposition of the cell grid over processes, from the cell occupancy alone (no MPI):
// the work of each cell, a work-balanced split along a space-filling curve, an equal-volume
// split for contrast, the owner of any cell, and each process's work, particles and halo.
//
// Cells are ordered along the Morton curve (the interleaved bits of the cell coordinates) and
// each process takes one contiguous stretch of the curve. The split is described by P start
// keys only, so every process computes the owner of any cell by a binary search, and all
// processes agree on the partition when they start from the same (reduced) histogram.
#pragma once

#include <array>
#include <cstdint>
#include <string_view>
#include <utility>
#include <vector>

#include "contactlab/kernels/cell_grid.hpp"
#include "contactlab/kernels/scene.hpp"

namespace contactlab {

// Particles per cell of a grid with linear numbering (key = (cz * G_y + cy) * G_x + cx).
struct CellHistogram {
  std::array<int, 3> dims{1, 1, 1};
  std::vector<std::uint32_t> count;  // one entry per cell

  std::uint64_t key(int cx, int cy, int cz) const {
    return (std::uint64_t(cz) * dims[1] + std::uint64_t(cy)) * dims[0] + std::uint64_t(cx);
  }
};

// The histogram of `scene` on `grid` (which must number its cells linearly). Adds to
// `histogram` when it already has the grid's size, so partial scenes can be summed.
void add_to_histogram(const CellGrid& grid, const Scene& scene, CellHistogram& histogram);

// Candidate pairs of a cell with the full 27-cell stencil: n_c times the particles of the
// cells around it (its own included). The work the detection loop does for the cell's homes.
std::uint64_t cell_work(const CellHistogram& histogram, int cx, int cy, int cz);

// The Morton key of a cell (21 bits per axis).
std::uint64_t morton_key(int cx, int cy, int cz);

enum class PartitionMethod {
  kWork,    // contiguous stretches of the curve with equal candidate-pair work
  kVolume,  // contiguous stretches of the curve with equal numbers of cells
};
std::string_view to_string(PartitionMethod method);
PartitionMethod parse_partition_method(std::string_view text);  // throws InputError

// The particles in curve order: cells by Morton key, and within a cell by input row (so the
// k-th particle of a cell is the one with k smaller input rows in that cell). The work split
// gives each particle the work of its cell's stencil (its candidates) and cuts the sequence
// where the running work crosses r W / P: every rank's work is W / P within one particle's
// work, even when one dense cell holds more than W / P (its particles then go to several ranks,
// each holding the others as ghosts). The volume split cuts the sequence of cells (every cell
// weighing 1, whole cells to a rank). Ranks may be left empty (more ranks than particles).
class Partition {
 public:
  Partition() = default;
  Partition(const CellHistogram& histogram, int ranks, PartitionMethod method);

  int ranks() const { return ranks_; }
  // The rank owning the k-th particle (0-based, by input row) of a cell.
  int owner(int cx, int cy, int cz, std::uint32_t k) const;
  // The ranks owning a cell's particles: first and last of a contiguous range; {-1, -1} for an
  // empty cell.
  std::pair<int, int> owners(int cx, int cy, int cz) const;
  // The linear keys (ascending) of the cells whose particles more than one rank owns: at most
  // ranks - 1 of them.
  std::vector<std::uint64_t> shared_cells() const;

  // Builds an O(cells) table making cell lookups O(1) instead of a binary search over the
  // occupied cells: worth it for many lookups, once the histogram's memory is freed.
  void index_cells();

  // Whether the cell holds particles (of the histogram the partition was made from).
  bool occupied(int cx, int cy, int cz) const { return find(cx, cy, cz) != nullptr; }
  // The largest work of one particle: the split's granularity.
  double particle_work_max() const { return particle_work_max_; }

 private:
  struct Cell {
    std::uint64_t key;     // Morton key
    std::uint64_t linear;  // linear key
    double before;         // curve position of the cell's start (work or cells before it)
    double per_particle;   // curve length of each particle (0 in the volume split)
    double width;          // curve length of the whole cell
    std::uint32_t count;
    int first = 0, last = 0;  // the ranks owning its first and last particle
  };
  const Cell* find(int cx, int cy, int cz) const;
  int owner_in(const Cell& cell, std::uint32_t k) const;
  int rank_at(double position) const;

  std::vector<Cell> cells_;  // occupied cells, by key
  std::array<int, 3> dims_{1, 1, 1};
  std::vector<std::uint32_t> index_;  // linear cell key -> its entry in cells_ (or UINT32_MAX)
  double total_ = 0.0;
  double particle_work_max_ = 0.0;
  int ranks_ = 1;
};

// What one process gets: its candidate-pair work, its particles, and the halo: the particles
// owned by others in the cells next to (in the 27-cell stencil of) the cells of its particles.
struct RankLoad {
  std::uint64_t work = 0;
  std::uint64_t particles = 0;
  std::uint64_t halo_particles = 0;
  std::uint64_t cells = 0;  // occupied cells it owns particles of
  // Ranks its ghosts come from: the messages of its halo exchange (one per source rank).
  std::uint64_t halo_sources = 0;
};

struct PartitionReport {
  std::vector<RankLoad> ranks;
  double work_imbalance = 0.0;      // max / mean - 1 of the work
  double particle_imbalance = 0.0;  // max / mean - 1 of the particles
  std::uint64_t total_work = 0;
  std::uint64_t max_cell_work = 0;      // n_c times its stencil's particles, the largest
  std::uint64_t max_particle_work = 0;  // the work split's granularity
  std::uint64_t total_halo = 0;
};

PartitionReport evaluate_partition(const CellHistogram& histogram, const Partition& partition);

// max / mean - 1 of the values (0 for none or an all-zero list).
double imbalance(const std::vector<std::uint64_t>& values);

}  // namespace contactlab
