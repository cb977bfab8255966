// `contactlab dem tile COLUMN --restart COLUMN.chk --into TARGET --copies NX,NY --checkpoint OUT`:
// a large bed from copies of a settled periodic column, cut to the target's silo, written as a
// checkpoint of the target's config (kernels/dem tile.hpp).
#include <fmt/core.h>

#include <memory>
#include <string>
#include <vector>

#include "cli_shared.hpp"
#include "contactlab/dem/checkpoint.hpp"
#include "contactlab/dem/config.hpp"
#include "contactlab/dem/tile.hpp"
#include "contactlab/kernels/atomic_file.hpp"
#include "contactlab/kernels/error.hpp"

namespace contactlab::cli {
namespace {

namespace dem = contactlab::dem;

struct DemTileCommand {
  std::string column_;
  std::string column_checkpoint_;
  std::string target_;
  std::vector<int> copies_;
  std::string out_;

  int run() const {
    const dem::DemConfig column = dem::read_dem_config(column_);
    const dem::DemConfig target = dem::read_dem_config(target_);
    prepare_output_file(out_);
    dem::Particles column_start = dem::make_particles(column);
    column_start.set_wall_count(column.settings.walls.size());
    const dem::CheckpointParts state = dem::read_checkpoint_parts(column_checkpoint_, column_start);
    const dem::TiledBed bed = dem::tile_column(column, state, target, {copies_[0], copies_[1]});
    const dem::TileReport& r = bed.report;
    dem::write_checkpoint(bed.parts.state, bed.parts.particles, bed.parts.pairs, bed.parts.frames,
                          out_);
    fmt::print(
        "dem tile: {} copies of '{}' at t = {:.6g} s ({} particles) laid under '{}': {} inside "
        "the silo{}, {} pairs of the list; the highest centre at z = {:.4g} m; wrote {} (a "
        "checkpoint of {}: run it with --restart)\n",
        r.copies, column.name, state.state.time_s, r.laid, target.name, r.kept,
        r.over_count > 0 ? fmt::format(" ({} more above the config's count left out)", r.over_count)
                         : std::string(),
        r.pairs, r.top_z, out_, target_);
    return 0;
  }
};

}  // namespace

Subcommand add_dem_tile_command(CLI::App& dem_app) {
  auto tile = std::make_shared<DemTileCommand>();
  CLI::App* app = dem_app.add_subcommand(
      "tile",
      "a large bed from copies of a settled periodic column, cut to the target config's silo and "
      "written as its checkpoint");
  app->add_option("column", tile->column_, "the column's config (periodic along x and y)")
      ->required();
  app->add_option("--restart", tile->column_checkpoint_, "the column's checkpoint to copy")
      ->required();
  app->add_option("--into", tile->target_,
                  "the target config: its lattice inside a cylinder gives the silo to cut to")
      ->required();
  app->add_option("--copies", tile->copies_, "copies along x and y, e.g. 6,6")
      ->required()
      ->delimiter(',')
      ->expected(2);
  app->add_option("--checkpoint", tile->out_, "the target's checkpoint to write")->required();
  return {app, [tile] { return tile->run(); }};
}

}  // namespace contactlab::cli
