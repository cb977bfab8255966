// contactlab: the command-line program. Registers the subcommands (one file each), runs the
// one given and maps errors to exit codes: 2 bad input, 3 out of memory, CLI11's for parsing.
#include <fmt/core.h>

#include <CLI/CLI.hpp>
#include <new>
#include <string>
#include <vector>

#include "cli_shared.hpp"
#include "contactlab/kernels/error.hpp"

int main(int argc, char** argv) {
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
                                                 cli::add_demo_command(app),
                                                 cli::add_dem_command(app)};

  try {
    app.parse(argc, argv);
    for (const cli::Subcommand& subcommand : subcommands) {
      if (*subcommand.app) return subcommand.run();
    }
    return 0;  // unreachable: exactly one subcommand is required
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const contactlab::InputError& e) {
    fmt::print(stderr, "contactlab: error: {}\n", e.what());
    return 2;
  } catch (const std::bad_alloc&) {
    fmt::print(stderr, "contactlab: error: out of memory\n");
    return 3;
  }
}
