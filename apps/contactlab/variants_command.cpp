// `contactlab variants`: list every variant and its parameters.
#include <fmt/core.h>

#include "cli_shared.hpp"
#include "contactlab/kernels/variant.hpp"

namespace contactlab::cli {
namespace {

int run_variants() {
  fmt::print("{}\n", variants_help());
  fmt::print("The paper's configurations:\n");
  for (const auto& v : paper_variants()) fmt::print("  {}\n", to_string(v));
  fmt::print("\nEvery loop/order/stencil (schedules as above, any k):\n");
  VariantSpace space = all_variants({});
  for (const auto& v : enumerate(space)) fmt::print("  {}\n", to_string(v));
  return 0;
}

}  // namespace

Subcommand add_variants_command(CLI::App& app) {
  return {app.add_subcommand("variants", "list every variant and its parameters"), run_variants};
}

}  // namespace contactlab::cli
