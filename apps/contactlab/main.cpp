// contactlab: the command-line program. Registers the subcommands (one file each), runs the
// one given and maps errors to exit codes: 2 bad input, 3 out of memory, CLI11's for parsing.
#include <fmt/core.h>

#include <CLI/CLI.hpp>
#include <cstdlib>
#include <new>
#include <string>
#include <vector>

#include "cli_shared.hpp"
#include "contactlab/kernels/error.hpp"

namespace {

// Whether this is a rank other than 0 of an MPI job asked for --mpi: it leaves messages that
// every rank would print alike (command-line errors, found before MPI starts) to rank 0.
bool quiet_mpi_rank(int argc, char** argv) {
  bool mpi = false;
  for (int i = 1; i < argc; ++i) mpi = mpi || std::string(argv[i]).rfind("--mpi", 0) == 0;
  if (!mpi) return false;
  for (const char* variable : {"OMPI_COMM_WORLD_RANK", "PMI_RANK", "PMIX_RANK", "SLURM_PROCID"}) {
    const char* value = std::getenv(variable);
    if (value) return std::string(value) != "0";
  }
  return false;
}

}  // namespace

// Exceptions other than those caught below are bugs: std::terminate, which names them, ends
// the program.
int main(int argc, char** argv) {  // NOLINT(bugprone-exception-escape)
  namespace cli = contactlab::cli;
  CLI::App app{"contactlab: particle contact detection — variants, measurement, tuning"};
  app.require_subcommand(1);
  std::string command_line;
  for (int i = 0; i < argc; ++i) command_line += (i ? " " : "") + std::string(argv[i]);

  const std::vector<cli::Subcommand> subcommands{cli::add_scene_command(app),
                                                 cli::add_detect_command(app, command_line),
                                                 cli::add_variants_command(app),
                                                 cli::add_sweep_command(app, command_line),
                                                 cli::add_tune_command(app, command_line),
                                                 cli::add_partition_command(app),
                                                 cli::add_emulate_command(app, command_line),
                                                 cli::add_demo_command(app),
                                                 cli::add_probe_command(app, command_line),
                                                 cli::add_dem_command(app, command_line)};

  try {
    app.parse(argc, argv);
    for (const cli::Subcommand& subcommand : subcommands) {
      if (*subcommand.app) return subcommand.run();
    }
    return 0;  // unreachable: exactly one subcommand is required
  } catch (const CLI::ParseError& e) {
    if (quiet_mpi_rank(argc, argv)) return e.get_exit_code();
    if (e.get_exit_code() == 0) return app.exit(e);  // --help
    // One line and exit status 2, as every other input error (CLI11's own exit printed a
    // second line and returned its codes 101 - 116).
    fmt::print(stderr, "contactlab: error: {} (see --help)\n", e.what());
    return 2;
  } catch (const contactlab::ReportedElsewhere&) {
    return 2;  // another MPI process printed the message
  } catch (const contactlab::InputError& e) {
    fmt::print(stderr, "contactlab: error: {}\n", e.what());
    return 2;
  } catch (const std::bad_alloc&) {
    fmt::print(stderr, "contactlab: error: out of memory\n");
    return 3;
  }
}
