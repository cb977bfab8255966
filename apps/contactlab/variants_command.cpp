// `contactlab variants`: list every variant and its parameters.
#include <fmt/core.h>

#include "cli_shared.hpp"
#include "contactlab/kernels/variant.hpp"

namespace contactlab::cli {
namespace {

int run_variants() {
  fmt::print(
      "Variants are written loop/order/stencil/schedule (loop/order/schedule = full stencil).\n");
  fmt::print(
      "  loop      cell | particle            parallel over grid cells (paper Fig. 4) or particles "
      "(Fig. 5)\n");
  fmt::print(
      "  order     unsorted | sorted | morton input order, grouped by cell (paper), or by cell in "
      "Morton order\n");
  fmt::print(
      "  stencil   full | half                27 cells, or own + 13 forward cells (each pair "
      "tested once)\n");
  fmt::print(
      "  schedule  static | static,k | dynamic,k | guided,k   (k >= 1; static = block "
      "partition)\n\n");
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
