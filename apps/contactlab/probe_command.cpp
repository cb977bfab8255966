// `contactlab probe`: the memory bandwidth this machine's threads draw at each working-set size
// (STREAM's triad) and the arithmetic they do from registers, printed and written as the
// machine file the emulations read
// (tuner/bandwidth_probe.hpp; docs/emulation.md, "Bandwidth").
#include <fmt/core.h>
#include <omp.h>

#include <cstdint>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cli_shared.hpp"
#include "contactlab/kernels/atomic_file.hpp"
#include "contactlab/kernels/error.hpp"
#include "contactlab/tuner/bandwidth_probe.hpp"
#include "contactlab/tuner/context.hpp"

namespace contactlab::cli {
namespace {

namespace tn = contactlab::tuner;

// "16M" -> 16 MiB: a whole number with an optional K, M or G (powers of 1024).
std::uint64_t size_of(const std::string& item) {
  std::size_t used = 0;
  unsigned long long value = 0;
  try {
    value = std::stoull(item, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  std::uint64_t scale = 1;
  if (used > 0 && used + 1 == item.size()) {
    const char unit = item.back();
    scale = unit == 'K' ? 1ull << 10 : unit == 'M' ? 1ull << 20 : unit == 'G' ? 1ull << 30 : 0;
    used += scale ? 1 : 0;
  }
  if (used == 0 || used != item.size() || value == 0) {
    throw InputError(fmt::format("--sizes: '{}' is not a size (a whole number, K, M or G)", item));
  }
  return value * scale;
}

struct ProbeCommand {
  std::string threads_;  // default: 1 .. the machine's cores
  std::string sizes_ = "16M,64M,256M,1G";
  int repetitions_ = 5;
  std::string json_out_;
  std::string command_line_;

  int run() const {
    if (!json_out_.empty()) prepare_output_file(json_out_);
    tn::ProbeOptions options;
    if (threads_.empty()) {
      for (int t = 1; t <= omp_get_num_procs(); ++t) options.threads.push_back(t);
    } else {
      options.threads = int_list(threads_, "--threads");
    }
    options.working_sets.clear();
    for (const std::string& item : split_list(sizes_))
      options.working_sets.push_back(size_of(item));
    options.repetitions = repetitions_;
    tn::validate(options);
    const tn::MachineProbe probe = tn::probe_bandwidth(options);
    fmt::print("{:>14} {:>8} {:>10}\n", "working set", "threads", "GB/s");
    for (const tn::ProbedWorkingSet& set : probe.working_sets) {
      for (const auto& [threads, bytes_per_s] : set.bytes_per_s) {
        fmt::print("{:>11.1f} MiB {:>8} {:>10.2f}\n", static_cast<double>(set.bytes) / (1 << 20),
                   threads, bytes_per_s / 1e9);
      }
    }
    // Whether P threads compute P times as fast: the arithmetic's rate over P x one thread's.
    const double one = probe.operations_per_s.front().second / probe.operations_per_s.front().first;
    fmt::print("\n{:>8} {:>14} {:>16}\n", "threads", "Gop/s", "of P x 1 thread");
    for (const auto& [threads, rate] : probe.operations_per_s) {
      fmt::print("{:>8} {:>14.2f} {:>16.2f}\n", threads, rate / 1e9, rate / (threads * one));
    }
    if (!json_out_.empty()) {
      const nlohmann::json doc = tn::probe_document(
          probe, options, tn::collect_context(command_line_, options.threads.back()));
      write_json(json_out_, doc);
    }
    return 0;
  }
};

}  // namespace

Subcommand add_probe_command(CLI::App& app, const std::string& command_line) {
  auto command = std::make_shared<ProbeCommand>();
  command->command_line_ = command_line;
  CLI::App* sub = app.add_subcommand(
      "probe",
      "the memory bandwidth this machine's threads draw (STREAM's triad), per working set, and "
      "the arithmetic they do from registers");
  sub->add_option("--threads", command->threads_,
                  "thread counts, ascending (default: 1 .. the machine's cores)");
  sub->add_option("--sizes", command->sizes_,
                  "working sets, the three arrays together: K, M or G (default 16M,64M,256M,1G)");
  sub->add_option("--repetitions", command->repetitions_,
                  "timed passes per point after one untimed; the best is kept (default 5)");
  sub->add_option("--json", command->json_out_,
                  "write the machine file the emulations read (docs/emulation.md)");
  return {sub, [command] { return command->run(); }};
}

}  // namespace contactlab::cli
