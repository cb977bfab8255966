// `contactlab emulate threads|mpi`: what detection would take on more threads or processes than
// this machine has (docs/emulation.md), every value labelled emulated or predicted, and checked
// against what this machine measures (threads up to its cores; `detect --mpi` result files).
#include <fmt/core.h>
#include <fmt/ranges.h>
#include <omp.h>

#include <algorithm>
#include <deque>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>

#include "cli_shared.hpp"
#include "contactlab/kernels/atomic_file.hpp"
#include "contactlab/kernels/error.hpp"
#include "contactlab/kernels/partition.hpp"
#include "contactlab/tuner/auto_variant.hpp"
#include "contactlab/tuner/context.hpp"
#include "contactlab/tuner/measured_kernel.hpp"
#include "contactlab/tuner/thread_emulation.hpp"
#include "contactlab/tuner_model/emulation.hpp"

namespace contactlab::cli {
namespace {

namespace tn = contactlab::tuner;

struct EmulateThreadsCommand {
  SceneOptions scene_;
  std::string variants_ =
      "particle/unsorted/full/static,cell/unsorted/full/static,particle/sorted/full/static,"
      "cell/sorted/full/static,particle/sorted/full/static,200,particle/sorted/half/static,"
      "cell/sorted/half/static,particle/sorted/half/static,200,particle/sorted/full/balanced,"
      "particle/sorted/half/balanced";
  std::string threads_ = "1,2,4,8,16";
  std::string measured_;  // default: 1 .. the machine's cores
  std::string chunk_threads_ = "2,4,8,16";
  int rounds_ = 7;
  MemoryOptions memory_;
  std::string json_out_;
  std::string cache_file_;
  bool recalibrate_ = false;
  std::string command_line_;

  int run() const {
    scene_.require_diameter();
    const std::optional<tn::MemorySystem> memory = memory_.load();
    if (!json_out_.empty()) prepare_output_file(json_out_);
    tn::ThreadEmulationOptions options;
    // Variants are separated by ';' or by ',' before a loop name (a schedule has commas).
    std::string text = variants_;
    for (const char* loop : {",particle/", ",cell/"}) {
      for (std::size_t at = text.find(loop); at != std::string::npos; at = text.find(loop, at)) {
        text[at] = ';';
      }
    }
    std::size_t start = 0;
    while (start <= text.size()) {
      const std::size_t end = std::min(text.find(';', start), text.size());
      const std::string item = text.substr(start, end - start);
      if (item.empty()) throw InputError("--variants: an empty item");
      options.variants.push_back(parse_variant(item));
      start = end + 1;
    }
    options.threads = int_list(threads_, "--threads");
    options.chunk_threads = int_list(chunk_threads_, "--chunk-threads");
    if (measured_.empty()) {
      options.measured_threads = {1};
      if (omp_get_num_procs() > 1) options.measured_threads.push_back(omp_get_num_procs());
    } else {
      options.measured_threads = int_list(measured_, "--measured-threads");
    }
    options.rounds = rounds_;
    options.memory = memory;
    validate(options);
    auto [scene, record] = scene_.load();
    tn::TuningCache cache(cache_file_.empty() ? tn::TuningCache::default_path() : cache_file_);
    const tn::Calibration calibration = tn::machine_calibration(
        cache, tn::structures_for(options.variants),
        *std::max_element(options.measured_threads.begin(), options.measured_threads.end()),
        recalibrate_);
    const tn::ThreadEmulation emulation =
        tn::emulate_threads(scene, scene_.diameter_, options, calibration);
    fmt::print("emulate threads: N {}, D {}; measured at {} thread(s), {} rounds\n", scene.size(),
               scene_.diameter_, fmt::join(options.measured_threads, ","), options.rounds);
    for (const tn::VariantEmulation& e : emulation.variants) {
      fmt::print("\n{}  (anchor scale {:.3f})\n", to_string(e.variant), e.anchor_scale);
      if (memory) {
        fmt::print("  bandwidth: {}; {:.0f} MB setup, {:.0f} MB loop, {:.0f} MB rows\n",
                   memory->describe(e.traffic.footprint_bytes), e.traffic.setup_bytes / 1e6,
                   e.traffic.loop_bytes / 1e6, e.traffic.rows_bytes / 1e6);
      }
      fmt::print("  {:>7} {:>12} {:>12} {:>9} {:>10}  source\n", "threads", "T_ALL [s]", "T_c [s]",
                 "speedup", memory ? "memory [s]" : "");
      for (const tn::EmulatedThreads& p : e.emulated) {
        fmt::print("  {:>7} {:>12.5f} {:>12.5f} {:>9.2f} {:>10}  emulated\n", p.threads,
                   p.total_s(), p.detect_s, p.speedup,
                   memory ? fmt::format("{:.5f}", p.memory_s) : std::string());
      }
      for (const tn::EmulationCheck& c : e.checks) {
        fmt::print(
            "  check at {} threads: T_ALL measured {:.5f} emulated {:.5f} ({:+.1f}%), T_c "
            "measured {:.5f} emulated {:.5f} ({:+.1f}%)\n",
            c.threads, c.measured_total_s, c.emulated_total_s,
            100.0 * tn::relative_error(c.emulated_total_s, c.measured_total_s), c.measured_detect_s,
            c.emulated_detect_s,
            100.0 * tn::relative_error(c.emulated_detect_s, c.measured_detect_s));
      }
    }
    for (const tn::EmulatedChunkStudy& s : emulation.chunk_study) {
      fmt::print("chunk study (emulated) {} threads {}: best k = {} ({:.5f} s), block {:.5f} s\n",
                 s.threads, to_string(s.variant.schedule.kind), s.best_chunk, s.best_detect_s,
                 s.block_detect_s);
    }
    if (!json_out_.empty()) {
      write_json(json_out_, tn::emulation_document(emulation, options,
                                                   tn::collect_context(command_line_, 1), record));
    }
    return 0;
  }
};

// Detection times of `detect --mpi replicated --json` result files: ranks, threads per rank, T_c.
struct MeasuredMpiRun {
  int ranks = 1, threads = 1;
  double detect_s = 0.0;
};

MeasuredMpiRun read_mpi_run(const std::string& path) {
  const tn::ResultFile file = tn::read_result_file(path);
  if (file.runs.empty() || !file.runs.front().aggregates) {
    throw InputError(fmt::format("{}: no successful run", path));
  }
  const tn::RunRecord& run = file.runs.front();
  if (!run.mpi) throw InputError(fmt::format("{}: not a detect --mpi result file", path));
  return {file.context.mpi_ranks, run.parameters.threads, run.aggregates->detect_s.median};
}

struct EmulateMpiCommand {
  SceneOptions scene_;
  std::string variant_ = "particle/sorted/full/static,200";
  std::string processes_ = "1,2,4,8,16,32,64,128,256,512,1024";
  int threads_per_rank_ = 16;
  std::uint32_t block_ = 200;
  NetworkOptions network_{.source =
                              "Tofu interconnect of the FX10 as commonly cited (about 1.5 us MPI "
                              "latency, 5 GB/s per link and direction); not measured here"};
  std::vector<std::string> measured_;
  int rounds_ = 5;
  bool measure_slowest_ = true;
  std::string json_out_;
  std::string cache_file_;
  bool recalibrate_ = false;
  std::string command_line_;

  int run() const;
};

int EmulateMpiCommand::run() const {
  scene_.require_diameter();
  if (!json_out_.empty()) prepare_output_file(json_out_);
  if (threads_per_rank_ < 1) throw InputError("--threads-per-rank must be >= 1");
  if (block_ < 1) throw InputError("--block must be >= 1");
  network_.check();
  const std::vector<int> processes = int_list(processes_, "--processes");
  std::vector<MeasuredMpiRun> measured;
  for (const std::string& path : measured_) measured.push_back(read_mpi_run(path));
  const Variant variant = parse_variant(variant_);
  auto [scene, record] = scene_.load();
  const double diameter = scene_.diameter_;

  tn::TuningCache cache(cache_file_.empty() ? tn::TuningCache::default_path() : cache_file_);
  const tn::Calibration calibration = tn::machine_calibration(cache, tn::structures_for({variant}),
                                                              omp_get_num_procs(), recalibrate_);
  const auto found = calibration.structures.find(tn::structure_key(variant));
  tn::MachineCosts costs =
      found != calibration.structures.end() ? found->second.costs : tn::MachineCosts{};
  // The loop's fixed cost is measured on this scene below (a rank with no block of the loop:
  // every rank pays it, and a rank of 1024 has little else); it replaces the calibrated
  // per-region cost, which the small calibration scenes fit poorly.
  costs.seconds_per_region = 0.0;
  tn::DetectionKernel kernel(scene, diameter);
  const LoopWork work = kernel.iteration_work(variant, 1);
  const tn::WorkView view{work.tests, work.homes, work.builds};
  const tn::PreparedWork prepared(view);
  const tn::CommunicationModel network{network_.latency_s, network_.bandwidth, network_.source};

  // Timed here, in interleaved rounds so that a slow spell of the machine touches all alike:
  // the whole loop at one thread (the anchor), a rank with no block (the fixed cost) and, for
  // every process count of the pure-MPI series, its slowest rank alone (which rank is slowest
  // does not depend on the anchor: every rank's time is the same increasing function of its
  // replay).
  const auto iterations = static_cast<std::uint32_t>(work.tests.size());
  std::vector<DetectOptions> parts(1);  // [0]: the rank with no block
  parts[0].blocks = HomeBlocks{block_, iterations / block_ + 2, iterations / block_ + 1};
  std::vector<int> slowest_rank;
  if (measure_slowest_) {
    for (const int p : processes) {
      slowest_rank.push_back(
          tn::predict_replicated(view, costs, 1.0, block_, p, 1, variant.schedule, network)
              .slowest_rank);
      DetectOptions part;
      part.blocks = HomeBlocks{block_, static_cast<std::uint32_t>(p),
                               static_cast<std::uint32_t>(slowest_rank.back())};
      parts.push_back(part);
    }
  }
  std::deque<tn::DetectionKernel> rank_kernels;
  for (const DetectOptions& part : parts) rank_kernels.emplace_back(scene, diameter, part);
  kernel.run(variant, 1);  // warm-ups
  for (tn::DetectionKernel& k : rank_kernels) k.run(variant, 1);
  std::vector<double> anchor_samples;
  std::vector<std::vector<double>> part_samples(parts.size());
  for (int round = 0; round < rounds_; ++round) {
    anchor_samples.push_back(kernel.run(variant, 1).phase_s("detect"));
    for (std::size_t k = 0; k < parts.size(); ++k) {
      part_samples[k].push_back(rank_kernels[k].run(variant, 1).phase_s("detect"));
    }
  }
  // A one-process point of the pure series times the same whole loop at one thread as the
  // anchor: both kernels' samples set the anchor (one noisy spell of 11 runs had put the anchor
  // 17 % above the same loop's other 11).
  for (std::size_t i = 0; measure_slowest_ && i < processes.size(); ++i) {
    if (processes[i] != 1) continue;
    anchor_samples.insert(anchor_samples.end(), part_samples[i + 1].begin(),
                          part_samples[i + 1].end());
    break;
  }
  const double one_thread_s = median(anchor_samples);
  const double fixed_s = std::min(median(part_samples[0]), one_thread_s / 2);
  std::vector<Summary> slowest_measured;
  for (std::size_t k = 1; k < parts.size(); ++k) {
    slowest_measured.push_back(summarize(part_samples[k]));
  }
  const tn::AnchoredLoop loop(prepared, costs, variant.schedule, one_thread_s - fixed_s);
  // The deal's locality at P processes: the slowest rank of P timed alone over its replay (the
  // loop less the fixed cost in both). A rank of the pure series holds every P-th block; a
  // thread of a hybrid rank (R ranks of T threads, P = R T, its schedule's chunk the block)
  // holds the same, so both series take the factor of their process count. Without it the
  // replay missed the measured slowest rank by -19 to -25 % at 4 to 1024 processes on the
  // paper's scene (the calibration scenes fit the caches whole; a share of every P-th block of
  // 1,024,000 particles does not).
  std::map<int, double> locality;
  for (std::size_t i = 0; i < slowest_measured.size(); ++i) {
    if (processes[i] <= 1) continue;
    const double replay = tn::predict_replicated(view, costs, loop.scale(), block_, processes[i], 1,
                                                 variant.schedule, network, fixed_s)
                              .compute_s -
                          fixed_s;
    const double alone = slowest_measured[i].median - fixed_s;
    if (replay > 0.0 && alone > 0.0) locality[processes[i]] = alone / replay;
  }
  auto localised = [&](const tn::MpiPrediction& p, int processes_dealt) {
    const auto factor = locality.find(processes_dealt);
    return factor == locality.end() ? p : tn::with_locality(p, factor->second, fixed_s);
  };

  // The decomposition's per-rank work and halo, for each rank count.
  const double reach = scene.has_diameters() ? scene.max_diameter() : diameter;
  const CellGrid grid(scene.box, reach, CellNumbering::kLinear);
  CellHistogram histogram;
  add_to_histogram(grid, scene, histogram);
  // A ghost travels as its coordinates, diameter and input row: four doubles and an index.
  constexpr double kBytesPerGhost = 4 * sizeof(double) + sizeof(std::uint64_t);

  struct Series {
    std::string mode, label;
    int threads_per_rank;
    std::vector<tn::MpiPrediction> points;
  };
  std::vector<Series> series{{"replicated", "pure MPI", 1, {}},
                             {"replicated",
                              fmt::format("hybrid ({} threads per rank)", threads_per_rank_),
                              threads_per_rank_,
                              {}},
                             {"decomposed", "distributed memory (pure MPI)", 1, {}}};
  for (const int p : processes) {
    series[0].points.push_back(
        localised(tn::predict_replicated(view, costs, loop.scale(), block_, p, 1, variant.schedule,
                                         network, fixed_s),
                  p));
    // Hybrid: ranks of threads_per_rank threads; below one full rank, one rank of p threads.
    const int threads = std::min(p, threads_per_rank_);
    const int hybrid_ranks = std::max(1, p / threads_per_rank_);
    series[1].points.push_back(
        localised(tn::predict_replicated(view, costs, loop.scale(), block_, hybrid_ranks, threads,
                                         variant.schedule, network, fixed_s),
                  hybrid_ranks * threads));
    const Partition partition(histogram, p, PartitionMethod::kWork);
    const PartitionReport report = evaluate_partition(histogram, partition);
    std::vector<tn::DecomposedRank> ranks;
    for (const RankLoad& load : report.ranks) {
      ranks.push_back({load.work, load.halo_particles, load.halo_sources});
    }
    // A decomposed rank holds only its particles and ghosts: its fixed cost shrinks with its
    // share like the rest (the whole scene's fixed cost is a replicated rank's).
    series[2].points.push_back(tn::predict_decomposed(ranks, report.total_work, one_thread_s, 1,
                                                      1.0, kBytesPerGhost, network));
  }

  fmt::print(
      "emulate mpi: N {}, D {}, {}; one-thread T_c {:.5f} s (median of {}), of which fixed "
      "{:.6f} s (a rank with no block); network {} s + bytes / {:.3g} B/s\n",
      scene.size(), diameter, to_string(variant), one_thread_s, rounds_, fixed_s,
      network_.latency_s, network_.bandwidth);
  nlohmann::json series_json = nlohmann::json::array();
  for (const Series& s : series) {
    fmt::print("\n{} (predicted)\n  {:>9} {:>6} {:>12} {:>12} {:>9} {:>10}\n", s.label, "processes",
               "ranks", "T_c [s]", "comm [s]", "speedup", "efficiency");
    const double base = s.points.front().detect_s();
    nlohmann::json points = nlohmann::json::array();
    for (std::size_t i = 0; i < s.points.size(); ++i) {
      const tn::MpiPrediction& m = s.points[i];
      const double speedup = base / m.detect_s();
      const int procs = processes[i];
      fmt::print("  {:>9} {:>6} {:>12.6f} {:>12.3g} {:>9.1f} {:>10.3f}\n", procs, m.ranks,
                 m.detect_s(), m.communication_s, speedup, speedup / procs);
      nlohmann::json point{{"processes", procs},
                           {"ranks", m.ranks},
                           {"threads_per_rank", m.threads_per_rank},
                           {"compute_s", m.compute_s},
                           {"communication_s", m.communication_s},
                           {"detect_s", m.detect_s()},
                           {"rank_imbalance", m.rank_imbalance},
                           {"locality_factor", m.locality},
                           {"speedup", speedup},
                           {"efficiency", speedup / procs}};
      if (&s == &series.front() && !slowest_measured.empty()) {
        const Summary& alone = slowest_measured[i];
        point["slowest_rank"] = slowest_rank[i];
        point["slowest_rank_measured_s"] = tn::interval_json(alone);
        fmt::print(
            "  {:>9} slowest rank {} measured alone: {:.6f} s (replayed loop {:.6f} s, locality "
            "{:.3f})\n",
            procs, slowest_rank[i], alone.median, m.replay_compute_s, m.locality);
      }
      points.push_back(std::move(point));
    }
    series_json.push_back({{"mode", s.mode},
                           {"threads_per_rank", s.threads_per_rank},
                           {"label", s.label},
                           {"points", points}});
  }
  nlohmann::json validation = nlohmann::json::array();
  for (const MeasuredMpiRun& m : measured) {
    const tn::MpiPrediction p =
        localised(tn::predict_replicated(view, costs, loop.scale(), block_, m.ranks, m.threads,
                                         variant.schedule, network, fixed_s),
                  m.ranks * m.threads);
    const bool oversubscribed = m.ranks * m.threads > omp_get_num_procs();
    fmt::print("check: {} ranks x {} threads: measured {:.5f} s, predicted {:.5f} s ({:+.1f}%){}\n",
               m.ranks, m.threads, m.detect_s, p.detect_s(),
               100.0 * tn::relative_error(p.detect_s(), m.detect_s),
               oversubscribed ? " (oversubscribed)" : "");
    validation.push_back({{"mode", "replicated"},
                          {"ranks", m.ranks},
                          {"threads_per_rank", m.threads},
                          {"measured_detect_s", m.detect_s},
                          {"predicted_detect_s", p.detect_s()},
                          {"relative_error", tn::relative_error(p.detect_s(), m.detect_s)},
                          {"oversubscribed", oversubscribed}});
  }
  // The replay against the slowest rank alone: before its locality factor, which is this
  // measurement (the series' compute holds it).
  for (std::size_t i = 0; i < slowest_measured.size(); ++i) {
    const tn::MpiPrediction& m = series[0].points[i];
    const double replayed = m.replay_compute_s;
    validation.push_back(
        {{"mode", "replicated, slowest rank alone"},
         {"ranks", m.ranks},
         {"threads_per_rank", 1},
         {"measured_detect_s", slowest_measured[i].median},
         {"predicted_detect_s", replayed},
         {"relative_error", tn::relative_error(replayed, slowest_measured[i].median)},
         {"oversubscribed", false}});
  }
  if (!json_out_.empty()) {
    nlohmann::json doc{
        {"schema_version", 1},
        {"kind", "contactlab-mpi-model"},
        {"label", "predicted"},
        {"context", tn::collect_context(command_line_, 1)},
        {"scene", record},
        {"variant", to_string(variant)},
        {"block", block_},
        {"one_thread_detect_s", one_thread_s},
        {"loop_fixed_s", fixed_s},
        {"model",
         {{"latency_s", network_.latency_s},
          {"bandwidth_bytes_per_s", network_.bandwidth},
          {"source", network_.source},
          {"compute",
           "replicated: each rank's blocks (block-cyclic) replayed under the variant's schedule "
           "with its threads, priced by the calibrated machine costs scaled to this scene's "
           "measured one-thread T_c and multiplied by the deal's locality factor at its process "
           "count (the slowest rank of the pure series timed alone over its replay: a rank or "
           "thread holding every P-th block), plus the loop's fixed cost measured on this scene "
           "(a rank with no block), plus one reduction of the contact counts; decomposed: each "
           "rank's "
           "candidate work (partition.hpp, work split) as its share of the one-thread T_c (its "
           "fixed cost shrinks with its local scene), after an all-to-all of counts and its halo "
           "(one message per source rank, 40 bytes per ghost). Not modelled: the network's "
           "contention and topology, the node's memory bandwidth shared by its ranks"}}},
        {"series", series_json},
        {"validation", validation}};
    write_json(json_out_, doc);
  }
  return 0;
}

// What both subcommands write and where their calibration comes from.
void add_output_options(CLI::App& app, std::string& json_out, std::string& cache_file,
                        bool& recalibrate) {
  app.add_option("--json", json_out, "write the document (docs/emulation.md)");
  app.add_option("--cache", cache_file, "tuning cache holding the machine's calibration");
  app.add_flag("--recalibrate", recalibrate, "fit the machine's cost model again");
}

}  // namespace

Subcommand add_emulate_command(CLI::App& app, const std::string& command_line) {
  CLI::App* sub = app.add_subcommand(
      "emulate", "more threads or processes than this machine has: emulated, checked here");
  sub->require_subcommand(1);
  auto threads = std::make_shared<EmulateThreadsCommand>();
  threads->command_line_ = command_line;
  CLI::App* t = sub->add_subcommand(
      "threads", "detection variants at thread counts beyond the cores (trace replay)");
  threads->scene_.add_to(*t, true);
  t->add_option(
      "--variants", threads->variants_,
      "variants, comma-separated (default: the paper's five, the two half-stencil block loops, "
      "particle/sorted/half/static,200 and the sorted particle loop's balanced blocks)");
  t->add_option("--threads", threads->threads_, "thread counts to emulate (1,2,4,8,16)");
  t->add_option("--measured-threads", threads->measured_,
                "thread counts timed here, from 1 (default 1 and the cores)");
  t->add_option("--chunk-threads", threads->chunk_threads_,
                "thread counts of the emulated chunk study (2,4,8,16)");
  t->add_option("--rounds", threads->rounds_, "interleaved rounds of timed runs (7)");
  threads->memory_.add_to(*t, "every emulated phase");
  add_output_options(*t, threads->json_out_, threads->cache_file_, threads->recalibrate_);

  auto mpi = std::make_shared<EmulateMpiCommand>();
  mpi->command_line_ = command_line;
  CLI::App* m = sub->add_subcommand(
      "mpi", "detection over 1..1024 MPI processes: each rank's work and a network model");
  mpi->scene_.add_to(*m, true);
  m->add_option("--variant", mpi->variant_, "variant (particle/sorted/full/static,200)");
  m->add_option("--processes", mpi->processes_, "process counts (1,2,4,...,1024)");
  m->add_option("--threads-per-rank", mpi->threads_per_rank_, "hybrid: threads per rank (16)");
  m->add_option("--block", mpi->block_, "replicated: block of the block-cyclic deal (200)");
  mpi->network_.add_to(*m);
  m->add_option("--measured", mpi->measured_,
                "detect --mpi replicated --json result files to check the model against")
      ->delimiter(',');
  m->add_option("--rounds", mpi->rounds_,
                "timed one-thread runs of the anchor and of each slowest rank (5)");
  m->add_flag("!--no-slowest-rank", mpi->measure_slowest_,
              "do not time the pure-MPI series' slowest rank alone at each process count");
  add_output_options(*m, mpi->json_out_, mpi->cache_file_, mpi->recalibrate_);
  std::function<int()> dem_mpi;
  add_emulate_dem_mpi_command(*sub, command_line, dem_mpi);
  return {sub, [=] {
            if (*t) return threads->run();
            if (*m) return mpi->run();
            return dem_mpi();
          }};
}

}  // namespace contactlab::cli
