// The replicated and decomposed detection of distributed_detect.hpp. Each step is either local
// work inside run_checked (errors agreed on at its end) or a collective every rank reaches.
#include "contactlab/mpi/distributed_detect.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>
#include <span>

#include "contactlab/kernels/atomic_file.hpp"
#include "contactlab/kernels/error.hpp"
#include "contactlab/kernels/partition.hpp"
#include "contactlab/kernels/scene_io.hpp"
#include "contactlab/mpi/runtime.hpp"
#include "contactlab/support/statistics.hpp"

namespace contactlab::mpi {

std::string_view to_string(Mode mode) {
  return mode == Mode::kReplicated ? "replicated" : "decomposed";
}

Mode parse_mode(std::string_view text) {
  if (text == "replicated") return Mode::kReplicated;
  if (text == "decomposed") return Mode::kDecomposed;
  throw InputError("unknown --mpi mode '" + std::string(text) + "' (replicated or decomposed)");
}

namespace {

// A particle on the move between ranks, with its input row as global id. Fixed size, so the
// exchanges are byte arrays of whole records.
struct Particle {
  std::uint32_t id;
  std::uint32_t unused;
  double x, y, z, d;
};

void append(std::vector<char>& out, const Particle& p) {
  const char* bytes = reinterpret_cast<const char*>(&p);
  out.insert(out.end(), bytes, bytes + sizeof p);
}

std::vector<Particle> unpack(const std::vector<char>& bytes) {
  std::vector<Particle> particles(bytes.size() / sizeof(Particle));
  if (!particles.empty()) std::memcpy(particles.data(), bytes.data(), bytes.size());
  return particles;
}

std::vector<Particle> particles_of(const Scene& scene, std::uint64_t first, std::uint64_t last,
                                   std::uint64_t id_offset) {
  std::vector<Particle> out;
  out.reserve(last - first);
  for (std::uint64_t i = first; i < last; ++i) {
    out.push_back({static_cast<std::uint32_t>(id_offset + i), 0, scene.x[i], scene.y[i], scene.z[i],
                   scene.has_diameters() ? scene.diameter[i] : 0.0});
  }
  return out;
}

void check_diameter(const DetectOptions& options, bool diameters) {
  if (!diameters && !(options.diameter > 0.0 && std::isfinite(options.diameter))) {
    throw InputError("diameter D must be a positive finite number (got " +
                     number_text(options.diameter) + ")");
  }
}

// The pairs (i << 32 | j, i < j, global ids) in the detector's last contacts (working ids,
// rows not canonicalised: the pairs are sorted later anyway) from the rows of input rows below
// `rows`; `global` maps input rows to global ids (identity when empty). Each pair is in the
// rows of both partners that list it, so keeping i < j takes it once.
std::vector<std::uint64_t> pairs_from(const ContactDetector& detector, std::size_t rows,
                                      const std::vector<std::uint32_t>& global) {
  const ContactList& list = detector.contacts();
  const std::span<const std::uint32_t> to_input = detector.working_to_input();
  auto global_of = [&](std::uint32_t working) -> std::uint64_t {
    const std::uint32_t input = to_input.empty() ? working : to_input[working];
    return global.empty() ? input : global[input];
  };
  // Two passes, counting first: the list is exactly as long as the pairs.
  std::vector<std::uint64_t> pairs;
  for (int pass = 0; pass < 2; ++pass) {
    std::uint64_t count = 0;
    for (std::size_t a = 0; a < list.particle_count(); ++a) {
      const auto row = list.partners_of(a);
      if (row.empty()) continue;
      const std::uint32_t input = to_input.empty() ? static_cast<std::uint32_t>(a) : to_input[a];
      if (input >= rows) continue;
      const std::uint64_t i = global.empty() ? input : global[input];
      for (const std::uint32_t b : row) {
        const std::uint64_t j = global_of(b);
        if (j <= i) continue;
        if (pass == 1) pairs.push_back(i << 32 | j);
        ++count;
      }
    }
    if (pass == 0) pairs.reserve(count);
  }
  return pairs;
}

void record_run(const DetectRun& run, RankReport& report) {
  report.registration_s = run.setup_s;
  report.detection_s = run.detect_s;
  report.candidate_tests = run.candidate_tests;
  report.max_cell_occupancy = run.max_cell_occupancy;
  for (int a = 0; a < 3; ++a) report.grid[a] = static_cast<std::uint32_t>(run.grid_dims[a]);
}

// Every rank loads the whole scene and visits its blocks of the loop.
void prepare_replicated(MPI_Comm comm, const SceneSource& source, const DetectOptions& options,
                        const MpiOptions& mpi, MpiRun& result, RankPart& part) {
  RankReport& report = result.local;
  part.mode = Mode::kReplicated;
  part.external = source.scene;
  const double t = MPI_Wtime();
  run_checked(comm, [&] {
    if (!source.path.empty()) {
      part.local = read_scene(source.path, source.text_box);
      part.external = nullptr;
    }
    check_diameter(options, part.scene().has_diameters());
  });
  report.read_s = MPI_Wtime() - t;
  result.particles = part.scene().size();
  report.owned_particles = part.scene().size();
  part.blocks = {mpi.block, static_cast<std::uint32_t>(result.ranks),
                 static_cast<std::uint32_t>(result.rank)};
  part.present = true;
}

// Each rank reads its share, the particles go to the owners of their cells, and each rank
// receives its halo; then detection with owned homes and ghosts in the grid.
void prepare_decomposed(MPI_Comm comm, const SceneSource& source, const DetectOptions& options,
                        const MpiOptions& mpi, MpiRun& result, RankPart& part) {
  RankReport& report = result.local;
  part.mode = Mode::kDecomposed;
  const int rank = result.rank, ranks = result.ranks;
  std::uint64_t n = 0;
  Box box;
  bool diameters = false;
  std::vector<Particle> read;
  double t = MPI_Wtime();
  run_checked(comm, [&] {
    auto share = [&](std::uint64_t total) {
      return std::pair{total * rank / ranks, total * (rank + 1) / ranks};
    };
    if (!source.path.empty() && is_binary_scene(source.path)) {
      const BinarySceneHeader header = read_binary_header(source.path);
      const auto [first, last] = share(header.n);
      const Scene rows = read_binary_rows(source.path, header, first, last);
      n = header.n;
      box = header.box;
      diameters = header.diameters;
      read = particles_of(rows, 0, rows.size(), first);
    } else {
      // Text files and generated scenes cannot be read in parts: the whole, then the share.
      Scene loaded;
      if (!source.path.empty()) loaded = read_scene(source.path, source.text_box);
      const Scene& whole = source.path.empty() ? *source.scene : loaded;
      const auto [first, last] = share(whole.size());
      n = whole.size();
      box = whole.box;
      diameters = whole.has_diameters();
      read = particles_of(whole, first, last, 0);
    }
    if (n >= UINT32_MAX) throw InputError("at most 2^32 - 2 particles are supported");
    check_diameter(options, diameters);
  });
  report.read_s = MPI_Wtime() - t;
  result.particles = n;

  t = MPI_Wtime();
  double largest = 0.0, reach = options.diameter;
  for (const Particle& p : read) largest = std::max(largest, p.d);
  MPI_Allreduce(&largest, &reach, 1, MPI_DOUBLE, MPI_MAX, comm);
  if (!diameters) reach = options.diameter;
  const double width = mpi.halo > 0.0 ? mpi.halo : reach;
  result.halo_width = width;
  std::optional<CellGrid> grid;
  CellHistogram histogram;  // this rank's share, then (reduced) every rank's
  run_checked(comm, [&] {
    if (!(mpi.halo >= 0.0 && std::isfinite(mpi.halo))) {
      throw InputError("--halo must be a finite number >= 0");
    }
    if (mpi.halo > 0.0 && mpi.halo < reach) {
      throw InputError("--halo " + number_text(mpi.halo) + " is below the contact distance " +
                       number_text(reach));
    }
    grid.emplace(box, width, CellNumbering::kLinear);
    if (!grid->dense_fits()) {  // the partition's histogram has an entry per cell
      throw InputError(
          "--mpi decomposed: the partition grid has more than 2^28 cells (D or "
          "--halo too small for the box)");
    }
    histogram.dims = grid->dims();
    histogram.count.assign(grid->cell_count(), 0);
    for (const Particle& p : read) {
      const auto c = grid->coords_of(p.x, p.y, p.z);
      ++histogram.count[histogram.key(c[0], c[1], c[2])];
    }
  });
  result.partition_grid = grid->dims();
  const int cells = static_cast<int>(histogram.count.size());
  MPI_Allreduce(MPI_IN_PLACE, histogram.count.data(), cells, MPI_UINT32_T, MPI_SUM, comm);
  Partition partition;
  // (cell key, index) of the read particles, sorted: by cell, then by input row.
  std::vector<std::pair<std::uint64_t, std::uint32_t>> order(read.size());
  std::vector<std::uint64_t> shared;  // keys of the cells whose particles several ranks own
  std::vector<std::uint32_t> mine_in_shared;
  run_checked(comm, [&] {
    partition = Partition(histogram, ranks, PartitionMethod::kWork);
    std::vector<std::uint32_t>().swap(histogram.count);  // the partition knows the occupied cells
    partition.index_cells();
    shared = partition.shared_cells();
    mine_in_shared.assign(shared.size(), 0);
    for (std::uint32_t i = 0; i < read.size(); ++i) {
      const auto c = grid->coords_of(read[i].x, read[i].y, read[i].z);
      order[i] = {histogram.key(c[0], c[1], c[2]), i};
      const auto it = std::lower_bound(shared.begin(), shared.end(), order[i].first);
      if (it != shared.end() && *it == order[i].first) ++mine_in_shared[it - shared.begin()];
    }
    std::sort(order.begin(), order.end());
  });
  // Within a shared cell (at most P - 1 of them) particles are ordered by input row, and shares
  // are contiguous row ranges: a rank's particles of the cell come after those that lower ranks
  // read (an exclusive scan of the counts).
  std::vector<std::uint32_t> earlier(shared.size(), 0);
  MPI_Exscan(mine_in_shared.data(), earlier.data(), static_cast<int>(shared.size()), MPI_UINT32_T,
             MPI_SUM, comm);
  if (rank == 0) std::fill(earlier.begin(), earlier.end(), 0u);
  std::vector<std::vector<char>> outgoing(ranks);
  run_checked(comm, [&] {
    std::uint64_t current = UINT64_MAX;
    std::uint32_t k = 0;  // the particle's index among its cell's particles, by input row
    std::pair<int, int> owners{-1, -1};
    std::array<int, 3> c{};
    for (const auto& [key, i] : order) {
      const Particle& p = read[i];
      if (key != current) {
        current = key;
        c = grid->coords_of(p.x, p.y, p.z);
        owners = partition.owners(c[0], c[1], c[2]);
        if (owners.first != owners.second) {
          k = earlier[std::lower_bound(shared.begin(), shared.end(), key) - shared.begin()];
        }
      } else {
        ++k;
      }
      const int owner =
          owners.first == owners.second ? owners.first : partition.owner(c[0], c[1], c[2], k);
      append(outgoing[owner], p);
    }
    std::vector<Particle>().swap(read);
    std::vector<std::pair<std::uint64_t, std::uint32_t>>().swap(order);
  });
  std::vector<std::uint64_t> received_counts;
  std::vector<Particle> owned = unpack(all_to_all_bytes(comm, outgoing, &received_counts));
  for (int r = 0; r < ranks; ++r) {
    if (r != rank) report.migrated_in += received_counts[r] / sizeof(Particle);
  }

  // The halo: a copy of each owned particle to every other rank owning particles in its cell
  // or an occupied cell next to it (the 27-cell stencil of cells at least the halo width
  // wide). The destinations are found once per cell.
  run_checked(comm, [&] {
    for (auto& out : outgoing) std::vector<char>().swap(out);
    const auto& dims = histogram.dims;
    std::vector<std::pair<std::uint64_t, std::uint32_t>> by_cell;  // (cell key, index in owned)
    by_cell.reserve(owned.size());
    for (std::uint32_t i = 0; i < owned.size(); ++i) {
      const auto c = grid->coords_of(owned[i].x, owned[i].y, owned[i].z);
      by_cell.emplace_back(histogram.key(c[0], c[1], c[2]), i);
    }
    std::sort(by_cell.begin(), by_cell.end());
    std::vector<std::pair<int, int>> ranges;
    std::vector<int> destinations;
    std::uint64_t current = UINT64_MAX;
    for (const auto& [key, i] : by_cell) {
      if (key != current) {
        current = key;
        const auto c = grid->coords_of(owned[i].x, owned[i].y, owned[i].z);
        ranges.clear();
        for (int z = std::max(c[2] - 1, 0); z <= std::min(c[2] + 1, dims[2] - 1); ++z) {
          for (int y = std::max(c[1] - 1, 0); y <= std::min(c[1] + 1, dims[1] - 1); ++y) {
            for (int x = std::max(c[0] - 1, 0); x <= std::min(c[0] + 1, dims[0] - 1); ++x) {
              if (!partition.occupied(x, y, z)) continue;
              ranges.push_back(partition.owners(x, y, z));
            }
          }
        }
        std::sort(ranges.begin(), ranges.end());
        destinations.clear();
        int next = 0;  // ranks below next are listed
        for (const auto& [a, b] : ranges) {
          for (int q = std::max(a, next); q <= b; ++q) {
            if (q != rank) destinations.push_back(q);
          }
          next = std::max(next, b + 1);
        }
      }
      for (const int q : destinations) {
        append(outgoing[q], owned[i]);
        ++report.halo_sent;
      }
    }
    std::sort(owned.begin(), owned.end(),
              [](const Particle& a, const Particle& b) { return a.id < b.id; });
  });
  const std::vector<char> halo_bytes = exchange_with_neighbours(comm, outgoing);
  std::vector<Particle> ghosts = unpack(halo_bytes);
  report.halo_bytes = halo_bytes.size();
  std::vector<std::vector<char>>().swap(outgoing);
  partition = Partition();  // its O(cells) index is no longer needed
  report.exchange_s = MPI_Wtime() - t;

  // The local scene: owned particles, then ghosts, each ascending by input row. Its box is the
  // particles' bounding box (so the detection grid is O(local volume), not the whole box).
  run_checked(comm, [&] {
    std::sort(ghosts.begin(), ghosts.end(),
              [](const Particle& a, const Particle& b) { return a.id < b.id; });
    report.owned_particles = owned.size();
    report.halo_particles = ghosts.size();
    if (owned.empty()) return;  // an empty subdomain: nothing to detect, ghosts unused
    Scene& local = part.local;
    std::vector<std::uint32_t>& global = part.global;
    local.reserve(owned.size() + ghosts.size());
    global.reserve(owned.size() + ghosts.size());
    std::array<double, 3> lo{std::numeric_limits<double>::max(), std::numeric_limits<double>::max(),
                             std::numeric_limits<double>::max()};
    std::array<double, 3> hi{std::numeric_limits<double>::lowest(),
                             std::numeric_limits<double>::lowest(),
                             std::numeric_limits<double>::lowest()};
    for (const auto* list : {&owned, &ghosts}) {
      for (const Particle& p : *list) {
        local.x.push_back(p.x);
        local.y.push_back(p.y);
        local.z.push_back(p.z);
        if (diameters) local.diameter.push_back(p.d);
        global.push_back(p.id);
        const double v[3] = {p.x, p.y, p.z};
        for (int a = 0; a < 3; ++a) {
          lo[a] = std::min(lo[a], v[a]);
          hi[a] = std::max(hi[a], v[a]);
        }
      }
    }
    for (int a = 0; a < 3; ++a) hi[a] = std::max(hi[a], lo[a] + width);
    local.box = Box{lo, hi};
    part.owned = owned.size();
    part.homes = {0, static_cast<std::uint32_t>(owned.size())};
    part.present = true;
    std::vector<Particle>().swap(ghosts);
    std::vector<Particle>().swap(owned);
  });
}

}  // namespace

DetectOptions RankPart::options_for(const DetectOptions& options) const {
  DetectOptions mine = options;
  mine.homes = homes;
  mine.blocks = blocks;
  // The half stencil misses owned-ghost pairs whose home would be the ghost.
  if (mode == Mode::kDecomposed) mine.variant.stencil = Stencil::kFull;
  return mine;
}

PreparedRun prepare(MPI_Comm comm, const SceneSource& source, const DetectOptions& options,
                    const MpiOptions& mpi_options) {
  PreparedRun prepared;
  prepared.start = MPI_Wtime();
  MpiRun& result = prepared.result;
  result.mode = mpi_options.mode;
  result.rank = rank_of(comm);
  result.ranks = size_of(comm);
  RankReport& report = result.local;
  report.rank = result.rank;
  report.threads = resolve_threads(options.threads);
  run_checked(comm, [&] {
    if (mpi_options.mode == Mode::kReplicated && mpi_options.block < 1) {
      throw InputError("--block must be >= 1");
    }
    if (source.path.empty() && !source.scene) throw InputError("no scene given");
    if (!mpi_options.contacts_out.empty() && result.rank == 0) {
      prepare_output_file(mpi_options.contacts_out);
    }
  });
  if (mpi_options.mode == Mode::kReplicated) {
    prepare_replicated(comm, source, options, mpi_options, result, prepared.part);
  } else {
    prepare_decomposed(comm, source, options, mpi_options, result, prepared.part);
  }
  return prepared;
}

MpiRun finish(MPI_Comm comm, PreparedRun& prepared, const DetectOptions& options,
              const MpiOptions& mpi_options) {
  MpiRun result = std::move(prepared.result);
  RankPart& part = prepared.part;
  RankReport& report = result.local;
  report.threads = resolve_threads(options.threads);
  std::vector<std::uint64_t> pairs;
  const auto repeat = static_cast<std::size_t>(std::max(1, mpi_options.repeat));
  std::vector<double> setup(repeat, 0.0), detect(repeat, 0.0), total(repeat, 0.0);
  run_checked(comm, [&] {
    if (!part.present) return;  // an empty subdomain
    ContactDetector detector;
    const DetectOptions mine = part.options_for(options);
    for (int w = 0; w < mpi_options.warmup; ++w) detector.run(part.scene(), mine);
    for (std::size_t r = 0; r < repeat; ++r) {
      const DetectRun run = detector.run(part.scene(), mine);
      record_run(run, report);
      setup[r] = run.setup_s;
      detect[r] = run.detect_s;
      total[r] = run.setup_s + run.detect_s;
    }
    report.registration_s = median(setup);
    report.detection_s = median(detect);
    const double output_start = MPI_Wtime();
    // Replicated: rows of other ranks' homes are empty (full stencil) or hold pairs found here
    // (half). Decomposed: rows below `owned` are the owned particles.
    detector.release_buffers();
    const std::size_t rows = part.mode == Mode::kDecomposed ? part.owned : part.scene().size();
    if (part.mode == Mode::kDecomposed) part.local = Scene{};
    pairs = pairs_from(detector, rows, part.global);
    report.output_s = MPI_Wtime() - output_start;
  });
  // Each repetition's slowest rank (ranks ran their repetitions without waiting for each other:
  // a repetition's time is as a job that ran once would see it).
  result.repetitions.setup_s.assign(repeat, 0.0);
  result.repetitions.detect_s.assign(repeat, 0.0);
  result.repetitions.total_s.assign(repeat, 0.0);
  const int n = static_cast<int>(repeat);
  MPI_Reduce(setup.data(), result.repetitions.setup_s.data(), n, MPI_DOUBLE, MPI_MAX, 0, comm);
  MPI_Reduce(detect.data(), result.repetitions.detect_s.data(), n, MPI_DOUBLE, MPI_MAX, 0, comm);
  MPI_Reduce(total.data(), result.repetitions.total_s.data(), n, MPI_DOUBLE, MPI_MAX, 0, comm);
  report.contact_pairs = pairs.size();
  MPI_Allreduce(&report.contact_pairs, &result.contact_pairs, 1, MPI_UINT64_T, MPI_SUM, comm);
  if (!mpi_options.contacts_out.empty()) {
    const double t = MPI_Wtime();
    write_pairs_parallel(comm, std::move(pairs), result.particles, mpi_options.contacts_out);
    report.output_s += MPI_Wtime() - t;
  }
  report.peak_rss_bytes = peak_rss_bytes();
  report.total_s = MPI_Wtime() - prepared.start;
  if (result.rank == 0) result.all.resize(result.ranks);
  MPI_Gather(&report, sizeof(RankReport), MPI_BYTE, result.all.data(), sizeof(RankReport), MPI_BYTE,
             0, comm);
  return result;
}

MpiRun detect(MPI_Comm comm, const SceneSource& source, const DetectOptions& options,
              const MpiOptions& mpi_options) {
  PreparedRun prepared = prepare(comm, source, options, mpi_options);
  return finish(comm, prepared, options, mpi_options);
}

}  // namespace contactlab::mpi
