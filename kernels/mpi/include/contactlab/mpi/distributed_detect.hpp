// Contact detection over MPI processes, in two modes (docs/mpi.md):
//
//  replicated  the paper's Section 4.4: every rank holds every particle; the detection loop's
//              iterations (the reordered particles) are dealt to ranks in blocks (block-cyclic,
//              block 200 by default); each rank's OpenMP threads share its blocks with the
//              variant's schedule. No communication but the output; memory does not scale.
//  decomposed  each rank reads its share of the file, the particles are split by work along
//              the Morton curve (partition.hpp, the same on every rank from the reduced cell
//              histogram), move to their owners, and each rank receives a halo of width W (the
//              others' particles in and next to its particles' cells). Homes = owned only, ghosts
//              sit in the grid (HomeRange), always with the full stencil. No rank holds every
//              particle (except a generated or text scene, which every rank makes or reads
//              whole before keeping its share).
//
// In both, each contact is found once globally and emitted by one rank as (i, j), i < j, in
// input rows; --contacts-out is written in parallel, sorted as the serial run writes it.
// Every phase ends with an agreement on errors (runtime.hpp), so a failure on one rank ends
// all of them with one message.
#pragma once

#include <mpi.h>

#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "contactlab/kernels/detector.hpp"
#include "contactlab/kernels/scene.hpp"

namespace contactlab::mpi {

enum class Mode { kReplicated, kDecomposed };
std::string_view to_string(Mode mode);
Mode parse_mode(std::string_view text);  // throws InputError

// Where the particles come from: a file (binary files are read in shares in decomposed mode)
// or a scene every rank already holds (generated, or a test's).
struct SceneSource {
  std::string path;
  Box text_box;                  // the box of a text file
  const Scene* scene = nullptr;  // used when path is empty
};

struct MpiOptions {
  Mode mode = Mode::kDecomposed;
  std::uint32_t block = 200;  // replicated: iterations per block of the block-cyclic deal
  double halo = 0.0;          // decomposed: halo width; 0 = D (or the largest diameter)
  std::string contacts_out;   // CSV of all contacts, empty = none
  // Untimed runs first (first touches), then timed runs: each rank reports its medians, and
  // rank 0 gets each repetition's slowest rank (MpiRun::repetitions).
  int warmup = 0;
  int repeat = 1;
};

// One rank's phases (seconds), particles and work. Plain data: gathered as bytes.
struct RankReport {
  int rank = 0;
  int threads = 0;
  double read_s = 0.0;          // its share of the scene (replicated: the whole scene)
  double exchange_s = 0.0;      // histogram, partition, migration to owners, halo
  double registration_s = 0.0;  // T_s: cell registration (and reordering)
  double detection_s = 0.0;     // T_c: pair tests and contact lists
  double output_s = 0.0;        // pairs to the writers, sorting, the parallel CSV write
  double total_s = 0.0;         // wall time of the whole run on this rank
  std::uint64_t owned_particles = 0;
  std::uint64_t halo_particles = 0;  // ghosts received
  std::uint64_t halo_sent = 0;       // copies of own particles sent as others' ghosts
  std::uint64_t halo_bytes = 0;      // bytes received in the halo exchange
  std::uint64_t migrated_in = 0;     // particles received from other ranks' reads
  std::uint64_t candidate_tests = 0;
  std::uint64_t contact_pairs = 0;  // contacts this rank emitted
  std::uint64_t peak_rss_bytes = 0;
  std::uint32_t max_cell_occupancy = 0;
  std::uint32_t grid[3] = {0, 0, 0};  // its detection grid
};

struct MpiRun {
  Mode mode = Mode::kDecomposed;
  int rank = 0, ranks = 1;
  std::uint64_t particles = 0;      // N
  std::uint64_t contact_pairs = 0;  // over all ranks
  double halo_width = 0.0;          // decomposed: the partition's cell width
  std::array<int, 3> partition_grid{};
  RankReport local;
  std::vector<RankReport> all;  // every rank's report, on rank 0 only
  // On rank 0, one entry per timed repetition: the largest over ranks of T_s, T_c and T_s + T_c.
  struct Repetitions {
    std::vector<double> setup_s, detect_s, total_s;
  } repetitions;
};

// One rank's part of the detection once the scene is read and (decomposed) the particles and
// halos exchanged: the scene this rank detects on and its homes. Replicated: the whole scene and
// its blocks of the loop (HomeBlocks); decomposed: its owned particles then its ghosts, homes
// the owned rows (HomeRange). What the tuner runs as one rank's kernel (`--variant auto`,
// `tune --mpi`).
struct RankPart {
  Mode mode = Mode::kDecomposed;
  bool present = false;               // false: an empty subdomain, nothing to detect
  const Scene* external = nullptr;    // the scene when the caller holds it (replicated)
  Scene local;                        // else the scene, held here
  std::vector<std::uint32_t> global;  // decomposed: the input row of each local particle
  std::size_t owned = 0;              // decomposed: local rows [0, owned) are the homes
  HomeRange homes{};
  HomeBlocks blocks{};
  const Scene& scene() const { return external ? *external : local; }
  // `options` restricted to this rank's homes (decomposed: always the full stencil).
  DetectOptions options_for(const DetectOptions& options) const;
};

struct PreparedRun {
  MpiRun result;  // what is known before the detection (read and exchange)
  RankPart part;
  double start = 0.0;
};

// detect() in two steps, both collective over `comm`: prepare() reads and exchanges (only
// options.diameter and options.threads are used), finish() detects with `options`, emits the
// pairs, writes contacts_out and gathers the reports. Between them the caller may run the
// rank's part as it likes (the tuner). Errors as detect().
PreparedRun prepare(MPI_Comm comm, const SceneSource& source, const DetectOptions& options,
                    const MpiOptions& mpi_options);
MpiRun finish(MPI_Comm comm, PreparedRun& prepared, const DetectOptions& options,
              const MpiOptions& mpi_options);

// Collective over `comm`. Throws InputError (on the rank reporting it) or ReportedElsewhere
// (on the others) when any rank fails; nothing is left at contacts_out then.
MpiRun detect(MPI_Comm comm, const SceneSource& source, const DetectOptions& options,
              const MpiOptions& mpi_options);

// The pairs (i << 32 | j, i < j, input rows of N particles) that this rank found, written as
// one CSV (header "i,j", sorted by i then j) without any rank holding them all: each goes to
// the rank holding the id range of its i, which sorts and formats its share; the shares are
// written at their offsets with MPI-IO into a temporary file that rank 0 renames into place.
void write_pairs_parallel(MPI_Comm comm, std::vector<std::uint64_t> pairs, std::uint64_t n,
                          const std::string& path);

}  // namespace contactlab::mpi
