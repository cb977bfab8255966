// The Morton-curve split of partition.hpp: particles in curve order (cells by Morton key, then
// input row), each taking its cell's stencil work, cut where the running work crosses
// multiples of the mean, so each process's work is the mean within one particle's work.
#include "contactlab/kernels/partition.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include "contactlab/kernels/error.hpp"

namespace contactlab {

void add_to_histogram(const CellGrid& grid, const Scene& scene, CellHistogram& histogram) {
  if (grid.numbering() != CellNumbering::kLinear) {
    throw InputError("add_to_histogram: the grid must number its cells linearly");
  }
  if (!grid.dense_fits()) {  // the histogram has an entry per cell
    throw InputError("add_to_histogram: the " + std::to_string(grid.dims()[0]) + "x" +
                     std::to_string(grid.dims()[1]) + "x" + std::to_string(grid.dims()[2]) +
                     " grid has more than 2^28 cells (the partition needs a dense histogram)");
  }
  if (histogram.dims != grid.dims() || histogram.count.size() != grid.cell_count()) {
    histogram.dims = grid.dims();
    histogram.count.assign(grid.cell_count(), 0);
  }
  for (std::size_t i = 0; i < scene.size(); ++i) {
    const auto c = grid.coords_of(scene.x[i], scene.y[i], scene.z[i]);
    ++histogram.count[histogram.key(c[0], c[1], c[2])];
  }
}

std::uint64_t cell_work(const CellHistogram& histogram, int cx, int cy, int cz) {
  const std::uint64_t own = histogram.count[histogram.key(cx, cy, cz)];
  if (own == 0) return 0;
  const auto& dims = histogram.dims;
  std::uint64_t around = 0;
  for (int z = std::max(cz - 1, 0); z <= std::min(cz + 1, dims[2] - 1); ++z) {
    for (int y = std::max(cy - 1, 0); y <= std::min(cy + 1, dims[1] - 1); ++y) {
      for (int x = std::max(cx - 1, 0); x <= std::min(cx + 1, dims[0] - 1); ++x) {
        around += histogram.count[histogram.key(x, y, z)];
      }
    }
  }
  return own * around;
}

std::uint64_t morton_key(int cx, int cy, int cz) {
  return CellGrid::wide_morton_part(0, cx) | CellGrid::wide_morton_part(1, cy) |
         CellGrid::wide_morton_part(2, cz);
}

std::string_view to_string(PartitionMethod method) {
  return method == PartitionMethod::kWork ? "work" : "volume";
}

PartitionMethod parse_partition_method(std::string_view text) {
  if (text == "work") return PartitionMethod::kWork;
  if (text == "volume") return PartitionMethod::kVolume;
  throw InputError("unknown partition method '" + std::string(text) + "' (work or volume)");
}

Partition::Partition(const CellHistogram& histogram, int ranks, PartitionMethod method)
    : dims_(histogram.dims), ranks_(ranks) {
  if (ranks < 1) throw InputError("partition: the rank count must be >= 1");
  const auto& dims = histogram.dims;
  if (std::max({dims[0], dims[1], dims[2]}) >= (1 << 21)) {
    throw InputError("partition: more than 2^21 cells along an axis");
  }
  std::vector<std::uint64_t> every_key;  // volume split: the curve position of a cell
  std::size_t occupied = 0;
  for (const std::uint32_t count : histogram.count) occupied += count > 0;
  cells_.reserve(occupied);  // exactly: this list is the largest thing a rank keeps of it
  for (int cz = 0; cz < dims[2]; ++cz) {
    for (int cy = 0; cy < dims[1]; ++cy) {
      for (int cx = 0; cx < dims[0]; ++cx) {
        const std::uint64_t key = morton_key(cx, cy, cz);
        if (method == PartitionMethod::kVolume) every_key.push_back(key);
        const std::uint32_t count = histogram.count[histogram.key(cx, cy, cz)];
        if (count == 0) continue;
        const double work = double(cell_work(histogram, cx, cy, cz));
        cells_.push_back({key, histogram.key(cx, cy, cz), 0.0, work / count, work, count});
      }
    }
  }
  std::sort(cells_.begin(), cells_.end(),
            [](const Cell& a, const Cell& b) { return a.key < b.key; });
  if (method == PartitionMethod::kVolume) {
    std::sort(every_key.begin(), every_key.end());
    for (Cell& cell : cells_) {
      cell.before = double(std::lower_bound(every_key.begin(), every_key.end(), cell.key) -
                           every_key.begin());
      cell.per_particle = 0.0;
      cell.width = 1.0;
    }
    total_ = double(every_key.size());
  } else {
    for (Cell& cell : cells_) {
      cell.before = total_;
      total_ += cell.width;
      particle_work_max_ = std::max(particle_work_max_, cell.per_particle);
    }
  }
  for (Cell& cell : cells_) {
    cell.first = owner_in(cell, 0);
    cell.last = owner_in(cell, cell.count - 1);
  }
}

std::vector<std::uint64_t> Partition::shared_cells() const {
  std::vector<std::uint64_t> keys;
  for (const Cell& cell : cells_) {
    if (cell.first != cell.last) keys.push_back(cell.linear);
  }
  std::sort(keys.begin(), keys.end());
  return keys;
}

void Partition::index_cells() {
  index_.assign(std::uint64_t(dims_[0]) * dims_[1] * dims_[2], UINT32_MAX);
  for (std::uint32_t e = 0; e < cells_.size(); ++e) index_[cells_[e].linear] = e;
}

int Partition::rank_at(double position) const {
  if (!(total_ > 0.0)) return 0;
  return std::min(ranks_ - 1, static_cast<int>(position / total_ * ranks_));
}

const Partition::Cell* Partition::find(int cx, int cy, int cz) const {
  if (!index_.empty()) {
    const std::uint64_t linear =
        (std::uint64_t(cz) * dims_[1] + std::uint64_t(cy)) * dims_[0] + std::uint64_t(cx);
    return index_[linear] == UINT32_MAX ? nullptr : &cells_[index_[linear]];
  }
  const std::uint64_t key = morton_key(cx, cy, cz);
  const auto it = std::lower_bound(cells_.begin(), cells_.end(), key,
                                   [](const Cell& c, std::uint64_t k) { return c.key < k; });
  return it != cells_.end() && it->key == key ? &*it : nullptr;
}

// The middle of the particle's stretch of the curve decides its rank.
int Partition::owner_in(const Cell& cell, std::uint32_t k) const {
  const double middle = cell.per_particle > 0.0 ? cell.before + (k + 0.5) * cell.per_particle
                                                : cell.before + 0.5 * cell.width;
  return rank_at(middle);
}

int Partition::owner(int cx, int cy, int cz, std::uint32_t k) const {
  const Cell* cell = find(cx, cy, cz);
  if (!cell) return -1;
  return cell->first == cell->last ? cell->first : owner_in(*cell, k);
}

std::pair<int, int> Partition::owners(int cx, int cy, int cz) const {
  const Cell* cell = find(cx, cy, cz);
  if (!cell) return {-1, -1};
  return {cell->first, cell->last};
}

double imbalance(const std::vector<std::uint64_t>& values) {
  if (values.empty()) return 0.0;
  std::uint64_t total = 0, largest = 0;
  for (const auto v : values) {
    total += v;
    largest = std::max(largest, v);
  }
  if (total == 0) return 0.0;
  return double(largest) * double(values.size()) / double(total) - 1.0;
}

PartitionReport evaluate_partition(const CellHistogram& histogram, const Partition& partition) {
  PartitionReport report;
  report.ranks.assign(partition.ranks(), RankLoad{});
  const auto& dims = histogram.dims;
  std::vector<std::uint64_t> owned_here;  // particles of the cell per rank of its owner range
  std::vector<std::pair<int, int>> ranges;
  // Per rank, the ranks it receives ghosts from.
  std::vector<std::vector<int>> sources(partition.ranks());
  // Pass 0: particles and work; pass 1: halos (of ranks that own particles).
  for (int pass = 0; pass < 2; ++pass) {
    for (int cz = 0; cz < dims[2]; ++cz) {
      for (int cy = 0; cy < dims[1]; ++cy) {
        for (int cx = 0; cx < dims[0]; ++cx) {
          const std::uint32_t count = histogram.count[histogram.key(cx, cy, cz)];
          if (count == 0) continue;
          const auto [first, last] = partition.owners(cx, cy, cz);
          owned_here.assign(last - first + 1, 0);
          for (std::uint32_t k = 0; k < count; ++k) {
            const int r = first == last ? first : partition.owner(cx, cy, cz, k);
            ++owned_here[r - first];
          }
          if (pass == 0) {
            const std::uint64_t work = cell_work(histogram, cx, cy, cz);
            const std::uint64_t per_particle = work / count;
            report.max_cell_work = std::max(report.max_cell_work, work);
            report.max_particle_work = std::max(report.max_particle_work, per_particle);
            for (int r = first; r <= last; ++r) {
              const std::uint64_t mine = owned_here[r - first];
              if (mine == 0) continue;
              report.ranks[r].particles += mine;
              report.ranks[r].work += mine * per_particle;
              report.ranks[r].cells += 1;
            }
            continue;
          }
          // Every rank owning particles in this cell or an occupied one next to it holds the
          // cell's other particles as ghosts, each once.
          ranges.clear();
          for (int z = std::max(cz - 1, 0); z <= std::min(cz + 1, dims[2] - 1); ++z) {
            for (int y = std::max(cy - 1, 0); y <= std::min(cy + 1, dims[1] - 1); ++y) {
              for (int x = std::max(cx - 1, 0); x <= std::min(cx + 1, dims[0] - 1); ++x) {
                if (histogram.count[histogram.key(x, y, z)] == 0) continue;
                ranges.push_back(partition.owners(x, y, z));
              }
            }
          }
          std::sort(ranges.begin(), ranges.end());
          int next = -1;  // ranks below next are counted
          for (const auto& [a, b] : ranges) {
            for (int q = std::max(a, next); q <= b; ++q) {
              if (report.ranks[q].particles == 0) continue;
              const std::uint64_t mine = q >= first && q <= last ? owned_here[q - first] : 0;
              report.ranks[q].halo_particles += count - mine;
              report.total_halo += count - mine;
              for (int r = first; r <= last; ++r) {
                // Kept unique as it grows: a rank has few sources but many shared cells.
                if (r != q && owned_here[r - first] > 0 &&
                    std::find(sources[q].begin(), sources[q].end(), r) == sources[q].end()) {
                  sources[q].push_back(r);
                }
              }
            }
            next = std::max(next, b + 1);
          }
        }
      }
    }
  }
  for (std::size_t r = 0; r < sources.size(); ++r) report.ranks[r].halo_sources = sources[r].size();
  std::vector<std::uint64_t> work, particles;
  for (const auto& load : report.ranks) {
    work.push_back(load.work);
    particles.push_back(load.particles);
    report.total_work += load.work;
  }
  report.work_imbalance = imbalance(work);
  report.particle_imbalance = imbalance(particles);
  return report;
}

}  // namespace contactlab
