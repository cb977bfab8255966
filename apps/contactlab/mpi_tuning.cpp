// The tuner under MPI: mpi_tuning.hpp.
#include "mpi_tuning.hpp"

#include <fmt/core.h>

#include <climits>
#include <filesystem>
#include <optional>

#include "contactlab/kernels/error.hpp"
#include "contactlab/mpi/runtime.hpp"
#include "contactlab/tuner/auto_variant.hpp"
#include "contactlab/tuner/measured_kernel.hpp"

namespace contactlab::cli {
namespace {

namespace tn = contactlab::tuner;

// Rank 0's text on every rank.
void broadcast_text(MPI_Comm comm, std::string& text) {
  std::uint64_t size = text.size();
  MPI_Bcast(&size, 1, MPI_UINT64_T, 0, comm);
  text.resize(size);
  MPI_Bcast(text.data(), static_cast<int>(size), MPI_CHAR, 0, comm);
}

// One rank's part of the detection as the tuner's kernel. Every call is collective (all ranks
// make the same calls in the same order, which the tuner guarantees when what it decides by is
// identical on every rank): the local work runs inside the error agreement, then times are
// reduced to the slowest rank's and counts summed, so every rank sees the same numbers.
class RankKernel final : public tn::MeasuredKernel {
 public:
  RankKernel(MPI_Comm comm, const mpi::RankPart& part, double diameter) : comm_(comm), part_(part) {
    if (part.present) {
      local_.emplace(part.scene(), diameter,
                     part.options_for(DetectOptions{Variant{}, diameter, 0, nullptr}));
    }
    // The first rank with a part: its values stand for all where each rank's own would differ.
    int mine = part.present ? mpi::rank_of(comm) : INT_MAX;
    MPI_Allreduce(&mine, &root_, 1, MPI_INT, MPI_MIN, comm);
    if (root_ == INT_MAX) root_ = 0;
  }
  std::string_view name() const override { return "contact_detection"; }
  std::string_view tuned_phase() const override { return "detect"; }

  tn::KernelRun run(const Variant& variant, int threads) override {
    tn::KernelRun r;
    mpi::run_checked(comm_, [&] {
      if (local_) r = local_->run(mine(variant), threads);
    });
    double seconds[2] = {r.phase_s("setup"), r.phase_s("detect")};
    MPI_Allreduce(MPI_IN_PLACE, seconds, 2, MPI_DOUBLE, MPI_MAX, comm_);
    std::uint64_t tests = 0;
    for (const auto& [name, count] : r.counts) {
      if (name == "candidate_tests") tests = count;
    }
    MPI_Allreduce(MPI_IN_PLACE, &tests, 1, MPI_UINT64_T, MPI_SUM, comm_);
    return {{{"setup", seconds[0]}, {"detect", seconds[1]}}, {{"candidate_tests", tests}}};
  }

  LoopWork iteration_work(const Variant& variant, int threads) override {
    // A rank without particles: one empty iteration, so the model and the chunk formulas have
    // something to price (its prediction is below every other rank's; the first rank's chunks
    // are used).
    LoopWork work{{0}, {1}, {1}};
    mpi::run_checked(comm_, [&] {
      if (local_) work = local_->iteration_work(mine(variant), threads);
    });
    return work;
  }

  std::pair<std::uint64_t, std::uint64_t> wrong_results() override {
    std::uint64_t wrong[2] = {0, 0};
    mpi::run_checked(comm_, [&] {
      if (!local_) return;
      const auto [missing, extra] = local_->wrong_results();
      wrong[0] = missing;
      wrong[1] = extra;
    });
    MPI_Allreduce(MPI_IN_PLACE, wrong, 2, MPI_UINT64_T, MPI_SUM, comm_);
    return {wrong[0], wrong[1]};
  }

  void max_over_parts(std::span<double> values) override {
    MPI_Allreduce(MPI_IN_PLACE, values.data(), static_cast<int>(values.size()), MPI_DOUBLE, MPI_MAX,
                  comm_);
  }
  void from_first_part(std::span<int> values) override {
    MPI_Bcast(values.data(), static_cast<int>(values.size()), MPI_INT, root_, comm_);
  }

 private:
  // Decomposed: the full stencil always (the half misses owned-ghost pairs).
  Variant mine(const Variant& variant) const {
    return part_.options_for(DetectOptions{variant, 0.0, 0, nullptr}).variant;
  }

  MPI_Comm comm_;
  const mpi::RankPart& part_;
  std::optional<tn::DetectionKernel> local_;
  int root_ = 0;
};

}  // namespace

tn::Calibration mpi_calibration(MPI_Comm comm, tn::TuningCache& cache,
                                const tn::TuneOptions& options, int threads, bool recalibrate) {
  std::string text;
  mpi::run_checked(comm, [&] {
    if (mpi::rank_of(comm) != 0) return;
    const tn::Calibration calibration =
        tn::machine_calibration(cache, options, threads, recalibrate);
    text = tn::TuningCache::calibration_text(calibration);
  });
  broadcast_text(comm, text);
  tn::Calibration calibration;
  mpi::run_checked(comm, [&] { calibration = tn::TuningCache::calibration_from_text(text); });
  return calibration;
}

tn::TuneReport tune_mpi_part(MPI_Comm comm, const mpi::PreparedRun& prepared,
                             const tn::SceneRecord& scene, double diameter, tn::TuneOptions options,
                             const tn::Calibration& calibration, const std::string& command_line,
                             const mpi::MpiOptions& mpi_options) {
  const mpi::RankPart& part = prepared.part;
  // The half stencil would be run as the full one in decomposed mode: screen it once only.
  if (part.mode == mpi::Mode::kDecomposed) options.stencils = {Stencil::kFull};
  int diameters = part.present && part.scene().has_diameters() ? 1 : 0;
  MPI_Allreduce(MPI_IN_PLACE, &diameters, 1, MPI_INT, MPI_MAX, comm);
  RankKernel kernel(comm, part, diameter);
  tn::TuneReport report;
  // The tuner's own errors (its options) are the same on every rank; the kernel agrees on
  // each local step's errors itself.
  mpi::run_checked(comm, [&] {
    report =
        tn::tune_kernel(kernel, scene, diameters ? std::nullopt : std::optional<double>(diameter),
                        options, calibration, command_line);
  });
  // The tuner decides by reduced numbers only, so every rank chose alike: checked, since a
  // rank detecting with another variant would still give right contacts and go unnoticed.
  const std::string chosen = to_string(report.chosen);
  std::string first = chosen;
  broadcast_text(comm, first);
  mpi::run_checked(comm, [&] {
    if (chosen != first) {
      throw InputError(fmt::format("tune: rank {} chose {} but rank 0 {} (a tuner bug)",
                                   mpi::rank_of(comm), chosen, first));
    }
  });
  tn::TuneMpi info;
  info.mode = std::string(mpi::to_string(part.mode));
  info.ranks = prepared.result.ranks;
  info.block = part.mode == mpi::Mode::kReplicated ? mpi_options.block : 0;
  info.halo_width = part.mode == mpi::Mode::kDecomposed ? prepared.result.halo_width : 0.0;
  report.document.mpi = info;
  return report;
}

std::string mpi_cache_setting(const mpi::PreparedRun& prepared, const tn::SceneRecord& scene,
                              const mpi::MpiOptions& mpi_options) {
  const mpi::Mode mode = prepared.part.mode;
  std::string setting =
      fmt::format("mpi {}, {} ranks, ", mpi::to_string(mode), prepared.result.ranks);
  setting += mode == mpi::Mode::kReplicated
                 ? fmt::format("block {}", mpi_options.block)
                 : fmt::format("halo {:.17g}", prepared.result.halo_width);
  if (scene.checksum.empty() && scene.path) {
    // Read in shares, the file has no checksum: its size and modification time stand for it.
    std::error_code error;
    const auto size = std::filesystem::file_size(*scene.path, error);
    const auto time = std::filesystem::last_write_time(*scene.path, error);
    setting += fmt::format(", file {} bytes, time {}", error ? 0 : size,
                           error ? 0 : time.time_since_epoch().count());
  }
  return setting;
}

Variant mpi_auto_variant(MPI_Comm comm, const mpi::PreparedRun& prepared,
                         const tn::SceneRecord& scene, double diameter, int threads,
                         const std::string& cache_file, const std::string& command_line,
                         const mpi::MpiOptions& mpi_options) {
  const bool reporter = mpi::rank_of(comm) == 0;
  tn::TuningCache cache(cache_file.empty() ? tn::TuningCache::default_path() : cache_file);
  const std::string setting = mpi_cache_setting(prepared, scene, mpi_options);
  std::string cached;
  mpi::run_checked(comm, [&] {
    if (!reporter) return;
    if (auto choice = cache.choice(scene, diameter, threads, setting)) cached = to_string(*choice);
  });
  broadcast_text(comm, cached);
  if (!cached.empty()) {
    if (reporter)
      tn::print_progress(fmt::format("--variant auto: {} (from {})", cached, cache.path()));
    return parse_variant(cached);
  }
  tn::TuneOptions options;
  options.threads = threads;
  const tn::Calibration calibration = mpi_calibration(comm, cache, options, threads, false);
  if (reporter) {
    tn::print_progress(
        fmt::format("--variant auto: no cached choice, tuning each rank's part ({})...", setting));
  }
  const tn::TuneReport report = tune_mpi_part(comm, prepared, scene, diameter, options, calibration,
                                              command_line, mpi_options);
  mpi::run_checked(comm, [&] {
    if (!reporter) return;
    cache.store_choice(scene, diameter, threads, report.chosen, 0.0, setting);
    tn::print_progress(
        fmt::format("--variant auto: {} (stored in {})", to_string(report.chosen), cache.path()));
  });
  return report.chosen;
}

}  // namespace contactlab::cli
