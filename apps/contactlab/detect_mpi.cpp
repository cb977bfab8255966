// `detect --mpi replicated|decomposed` and `tune --mpi`: the MPI paths of the detect and tune
// commands (docs/mpi.md).
#include "detect_mpi.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <cstdio>
#include <optional>

#include "contactlab/kernels/atomic_file.hpp"
#include "contactlab/kernels/error.hpp"
#include "contactlab/kernels/partition.hpp"
#include "contactlab/kernels/scene_io.hpp"
#include "contactlab/mpi/distributed_detect.hpp"
#include "contactlab/mpi/runtime.hpp"
#include "contactlab/tuner/context.hpp"
#include "contactlab/tuner/result_schema.hpp"
#include "contactlab/tuner/tune_report.hpp"
#include "mpi_errors.hpp"
#include "mpi_tuning.hpp"

namespace contactlab::cli {
namespace {

namespace tn = contactlab::tuner;

tn::MpiRankRecord to_record(const mpi::RankReport& r) {
  tn::MpiRankRecord out;
  out.rank = r.rank;
  out.threads = r.threads;
  out.read_s = r.read_s;
  out.exchange_s = r.exchange_s;
  out.registration_s = r.registration_s;
  out.detection_s = r.detection_s;
  out.output_s = r.output_s;
  out.total_s = r.total_s;
  out.owned_particles = r.owned_particles;
  out.halo_particles = r.halo_particles;
  out.halo_sent = r.halo_sent;
  out.halo_bytes = r.halo_bytes;
  out.migrated_in = r.migrated_in;
  out.candidate_tests = r.candidate_tests;
  out.contact_pairs = r.contact_pairs;
  out.peak_rss_bytes = r.peak_rss_bytes;
  return out;
}

// The run as one record: each repetition's times are its slowest rank's (T_c = max over ranks
// of T_c, T_ALL = max of T_s + T_c); the ranks' median T_c stand where threads' busy times
// would.
tn::RunRecord make_record(const mpi::MpiRun& run, const MpiDetectRequest& request,
                          const std::string& variant, tn::SceneRecord scene) {
  tn::RunRecord record;
  record.parameters.variant = variant;
  record.parameters.threads = run.local.threads;
  record.parameters.scene = std::move(scene);
  record.parameters.repetition.repeat = request.repeat;
  record.parameters.repetition.warmup = request.warmup;
  std::vector<double> busy;
  std::vector<std::uint64_t> tests;
  tn::RunWork work;
  tn::MpiRecord m;
  m.mode = std::string(mpi::to_string(run.mode));
  m.ranks = run.ranks;
  m.block = run.mode == mpi::Mode::kReplicated ? request.mpi.block : 0;
  m.halo_width = run.mode == mpi::Mode::kDecomposed ? run.halo_width : 0.0;
  for (const mpi::RankReport& r : run.all) {
    busy.push_back(r.detection_s);
    tests.push_back(r.candidate_tests);
    work.candidate_tests += r.candidate_tests;
    work.max_cell_occupancy = std::max(work.max_cell_occupancy, r.max_cell_occupancy);
    m.max_peak_rss_bytes = std::max(m.max_peak_rss_bytes, r.peak_rss_bytes);
    m.per_rank.push_back(to_record(r));
  }
  m.work_imbalance = imbalance(tests);
  work.contact_pairs = run.contact_pairs;
  work.grid = run.mode == mpi::Mode::kDecomposed
                  ? run.partition_grid
                  : std::array<int, 3>{int(run.local.grid[0]), int(run.local.grid[1]),
                                       int(run.local.grid[2])};
  record.samples.setup_s = run.repetitions.setup_s;
  record.samples.detect_s = run.repetitions.detect_s;
  record.samples.total_s = run.repetitions.total_s;
  record.samples.thread_busy_s.assign(run.repetitions.detect_s.size(), busy);
  record.samples.imbalance.assign(run.repetitions.detect_s.size(), load_imbalance(busy));
  tn::RunAggregates a;
  a.setup_s = summarize(record.samples.setup_s);
  a.detect_s = summarize(record.samples.detect_s);
  a.total_s = summarize(record.samples.total_s);
  a.imbalance = summarize(record.samples.imbalance);
  a.thread_busy_median_s = busy;
  a.repetitions = static_cast<int>(run.repetitions.detect_s.size());
  a.warmup_runs = request.warmup;
  a.measurement_s = 0.0;
  for (const auto& r : run.all) a.measurement_s = std::max(a.measurement_s, r.total_s);
  record.aggregates = a;
  record.work = work;
  record.phases = {{"setup", a.setup_s}, {"detect", a.detect_s}};
  record.work_counts = {{"candidate_tests", work.candidate_tests},
                        {"contact_pairs", work.contact_pairs},
                        {"max_cell_occupancy", work.max_cell_occupancy}};
  record.mpi = std::move(m);
  return record;
}

void print_run(const mpi::MpiRun& run, const Variant& variant) {
  fmt::print("mpi {}  ranks {}  threads/rank {}  N {}  contacts {}  variant {}\n",
             mpi::to_string(run.mode), run.ranks, run.local.threads, run.particles,
             run.contact_pairs, to_string(variant));
  fmt::print("{:>5} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>10} {:>9} {:>12} {:>9}\n", "rank",
             "read", "exchange", "T_s", "T_c", "output", "total", "owned", "halo", "tests",
             "RSS MiB");
  double t_c = 0, t_all = 0;
  std::uint64_t rss = 0;
  for (const auto& r : run.all) {
    fmt::print(
        "{:>5} {:>8.4f} {:>8.4f} {:>8.4f} {:>8.4f} {:>8.4f} {:>8.4f} {:>10} {:>9} {:>12} "
        "{:>9.1f}\n",
        r.rank, r.read_s, r.exchange_s, r.registration_s, r.detection_s, r.output_s, r.total_s,
        r.owned_particles, r.halo_particles, r.candidate_tests,
        double(r.peak_rss_bytes) / (1 << 20));
    t_c = std::max(t_c, r.detection_s);
    t_all = std::max(t_all, r.registration_s + r.detection_s);
    rss = std::max(rss, r.peak_rss_bytes);
  }
  fmt::print("max over ranks: T_c {:.6f} s  T_ALL = T_s + T_c {:.6f} s  peak RSS {:.1f} MiB\n", t_c,
             t_all, double(rss) / (1 << 20));
}

// Where the ranks get the particles: a binary file in decomposed mode is read in shares by the
// ranks; anything else is made or read whole on every rank (the description then carries its
// checksum). Local work: run inside the error agreement.
struct OpenedSource {
  mpi::SceneSource source;
  std::optional<std::pair<Scene, tn::SceneRecord>> loaded;
  tn::SceneRecord record;
};

void open_source(const SceneOptions& scene, mpi::Mode mode, OpenedSource& out) {
  if (mode == mpi::Mode::kDecomposed && !scene.input_.empty() && is_binary_scene(scene.input_)) {
    const BinarySceneHeader header = read_binary_header(scene.input_);
    if (!header.diameters) scene.require_diameter();
    out.source.path = scene.input_;
    out.record.kind = "file";
    out.record.path = scene.input_;
    out.record.n = header.n;
    if (!header.diameters) out.record.diameter = scene.diameter_;
    const Box& b = header.box;
    out.record.box = {b.lo[0], b.lo[1], b.lo[2], b.hi[0], b.hi[1], b.hi[2]};
  } else {
    out.loaded.emplace(scene.load());
    out.source.scene = &out.loaded->first;
    out.record = out.loaded->second;
  }
}

}  // namespace

int run_detect_mpi(const MpiDetectRequest& request) {
  mpi::Session session(nullptr, nullptr);
  const MPI_Comm comm = MPI_COMM_WORLD;
  const int rank = mpi::rank_of(comm);
  return with_agreed_errors(comm, [&] {
    mpi::MpiOptions options;
    Variant variant;
    const bool automatic = request.variant == "auto";
    OpenedSource opened;
    mpi::run_checked(comm, [&] {
      request.check_options();
      options.mode = mpi::parse_mode(request.mpi.mode);
      options.block = request.mpi.block;
      options.halo = request.mpi.halo;
      options.contacts_out = request.contacts_out;
      options.warmup = request.warmup;
      options.repeat = request.repeat;
      if (!automatic) variant = parse_variant(request.variant);
      if (!request.json_out.empty() && rank == 0) prepare_output_file(request.json_out);
      open_source(*request.scene, options.mode, opened);
    });
    DetectOptions detect_options{variant, request.scene->diameter_, request.threads, nullptr};
    mpi::PreparedRun prepared = mpi::prepare(comm, opened.source, detect_options, options);
    if (automatic) {
      detect_options.variant = mpi_auto_variant(
          comm, prepared, opened.record, request.scene->diameter_, resolve_threads(request.threads),
          request.cache_file, request.command_line, options);
    }
    if (options.mode == mpi::Mode::kDecomposed) detect_options.variant.stencil = Stencil::kFull;
    variant = detect_options.variant;
    const mpi::MpiRun run = mpi::finish(comm, prepared, detect_options, options);
    mpi::run_checked(comm, [&] {
      if (rank != 0) return;
      print_run(run, variant);
      if (request.json_out.empty()) return;
      tn::ResultFile result;
      result.context = tn::collect_context(request.command_line, run.local.threads);
      result.runs.push_back(make_record(run, request, to_string(variant), opened.record));
      tn::write_result_file(request.json_out, result);
    });
    return 0;
  });
}

int run_tune_mpi(const MpiTuneRequest& request) {
  mpi::Session session(nullptr, nullptr);
  const MPI_Comm comm = MPI_COMM_WORLD;
  const int rank = mpi::rank_of(comm);
  return with_agreed_errors(comm, [&] {
    mpi::MpiOptions options;
    tn::TuneOptions tune_options;
    OpenedSource opened;
    mpi::run_checked(comm, [&] {
      request.check_options();
      tune_options = request.options();
      options.mode = mpi::parse_mode(request.mpi.mode);
      options.block = request.mpi.block;
      options.halo = request.mpi.halo;
      if (!request.json_out.empty() && rank == 0) prepare_output_file(request.json_out);
      open_source(*request.scene, options.mode, opened);
    });
    const double diameter = request.scene->diameter_;
    const int threads = tune_options.threads;
    mpi::PreparedRun prepared = mpi::prepare(
        comm, opened.source, DetectOptions{Variant{}, diameter, threads, nullptr}, options);
    tn::TuningCache cache(request.cache_file.empty() ? tn::TuningCache::default_path()
                                                     : request.cache_file);
    const tn::Calibration calibration =
        mpi_calibration(comm, cache, tune_options, threads, request.recalibrate);
    const tn::TuneReport report =
        tune_mpi_part(comm, prepared, opened.record, diameter, tune_options, calibration,
                      request.command_line, options);
    const std::string setting = mpi_cache_setting(prepared, opened.record, options);
    mpi::run_checked(comm, [&] {
      if (rank != 0) return;
      fmt::print("{}: every time is the slowest rank's\n", setting);
      request.print(report.document);
      if (!tune_options.predict_only) {
        cache.store_choice(opened.record, diameter, threads, report.chosen, 0.0, setting);
      }
      if (!request.json_out.empty()) {
        write_file_atomically(request.json_out, [&](std::ostream& out) {
          out << tn::to_json_value(report.document).dump(2) << '\n';
        });
      }
    });
    return 0;
  });
}

}  // namespace contactlab::cli
