// `contactlab partition`: the spatial decomposition `detect --mpi decomposed` would use, for any
// rank count and without MPI: each rank's work, particles and halo, and the imbalance, for the
// work-balanced split and the equal-volume split.
#include <fmt/core.h>

#include <algorithm>
#include <memory>
#include <nlohmann/json.hpp>

#include "cli_shared.hpp"
#include "contactlab/kernels/atomic_file.hpp"
#include "contactlab/kernels/error.hpp"
#include "contactlab/kernels/partition.hpp"

namespace contactlab::cli {
namespace {

// Up to this many ranks every rank is printed (all are in the JSON file).
constexpr int kPrintedRanks = 64;

struct PartitionCommand {
  SceneOptions scene_;
  int ranks_ = 0;
  double halo_ = 0.0;
  bool all_ranks_ = false;
  std::string json_out_;

  void add_to(CLI::App& sub) {
    scene_.add_to(sub, true);
    sub.add_option("--ranks", ranks_, "number of MPI processes to split for (>= 1)")->required();
    sub.add_option("--halo", halo_,
                   "halo width (default: D, or the largest diameter); the cells are this wide");
    sub.add_flag("--all-ranks", all_ranks_,
                 fmt::format("print every rank (default: only up to {} ranks)", kPrintedRanks));
    sub.add_option("--json", json_out_, "write the per-rank loads as JSON");
  }
  int run() const;
};

nlohmann::json to_json(const PartitionReport& report, PartitionMethod method) {
  nlohmann::json ranks = nlohmann::json::array();
  for (std::size_t r = 0; r < report.ranks.size(); ++r) {
    const RankLoad& load = report.ranks[r];
    ranks.push_back({{"rank", r},
                     {"work", load.work},
                     {"particles", load.particles},
                     {"halo_particles", load.halo_particles},
                     {"halo_sources", load.halo_sources},
                     {"cells", load.cells}});
  }
  return {{"method", std::string(to_string(method))},
          {"work_imbalance", report.work_imbalance},
          {"particle_imbalance", report.particle_imbalance},
          {"total_work", report.total_work},
          {"max_cell_work", report.max_cell_work},
          {"max_particle_work", report.max_particle_work},
          {"total_halo_particles", report.total_halo},
          {"ranks", ranks}};
}

void print_report(const PartitionReport& report, PartitionMethod method, bool every_rank) {
  fmt::print("\n{} split: work imbalance {:.2f}%  particle imbalance {:.2f}%  halo total {}\n",
             to_string(method), 100.0 * report.work_imbalance, 100.0 * report.particle_imbalance,
             report.total_halo);
  const double mean_work = double(report.total_work) / double(report.ranks.size());
  fmt::print("  of the mean rank work: largest cell's {:.2f}%, largest particle's {:.4f}%\n",
             mean_work > 0 ? 100.0 * double(report.max_cell_work) / mean_work : 0.0,
             mean_work > 0 ? 100.0 * double(report.max_particle_work) / mean_work : 0.0);
  if (!every_rank) return;
  fmt::print("  {:>6} {:>14} {:>10} {:>10} {:>9}\n", "rank", "work", "particles", "halo",
             "work/mean");
  for (std::size_t r = 0; r < report.ranks.size(); ++r) {
    const RankLoad& load = report.ranks[r];
    fmt::print("  {:>6} {:>14} {:>10} {:>10} {:>9.4f}\n", r, load.work, load.particles,
               load.halo_particles, mean_work > 0 ? double(load.work) / mean_work : 0.0);
  }
}

int PartitionCommand::run() const {
  if (ranks_ < 1) throw InputError("--ranks must be >= 1");
  if (halo_ < 0.0) throw InputError("--halo must be >= 0");
  if (!json_out_.empty()) prepare_output_file(json_out_);
  auto [scene, record] = scene_.load();
  const double reach = scene.has_diameters() ? scene.max_diameter() : scene_.diameter_;
  if (halo_ > 0.0 && halo_ < reach) {
    throw InputError(fmt::format("--halo {} is below the contact distance {}", halo_, reach));
  }
  const double width = std::max(halo_, reach);
  const CellGrid grid(scene.box, width, CellNumbering::kLinear);
  CellHistogram histogram;
  add_to_histogram(grid, scene, histogram);
  fmt::print("N {}  cell width {}  grid {}x{}x{}  ranks {}\n", scene.size(), width, grid.dims()[0],
             grid.dims()[1], grid.dims()[2], ranks_);

  nlohmann::json methods = nlohmann::json::array();
  for (const PartitionMethod method : {PartitionMethod::kWork, PartitionMethod::kVolume}) {
    Partition partition(histogram, ranks_, method);
    partition.index_cells();
    const PartitionReport report = evaluate_partition(histogram, partition);
    print_report(report, method, all_ranks_ || ranks_ <= kPrintedRanks);
    methods.push_back(to_json(report, method));
  }
  if (!json_out_.empty()) {
    const nlohmann::json document{{"kind", "contactlab-partition"},
                                  {"schema_version", 1},
                                  {"particles", scene.size()},
                                  {"scene_checksum", record.checksum},
                                  {"cell_width", width},
                                  {"grid", grid.dims()},
                                  {"ranks", ranks_},
                                  {"methods", methods}};
    write_file_atomically(json_out_, [&](std::ostream& out) { out << document.dump(2) << '\n'; });
  }
  return 0;
}

}  // namespace

Subcommand add_partition_command(CLI::App& app) {
  auto command = std::make_shared<PartitionCommand>();
  CLI::App* sub = app.add_subcommand(
      "partition", "work, particles and halo per rank of the MPI decomposition (no MPI needed)");
  command->add_to(*sub);
  return {sub, [command] { return command->run(); }};
}

}  // namespace contactlab::cli
