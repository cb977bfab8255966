// `contactlab scene`: generate a scene and write it to a file.
#include <fmt/core.h>

#include <memory>

#include "cli_shared.hpp"
#include "contactlab/kernels/atomic_file.hpp"
#include "contactlab/kernels/scene_io.hpp"

namespace contactlab::cli {
namespace {

struct SceneCommand {
  SceneOptions scene_;
  std::string out_;

  int run() const {
    scene_.require_diameter();
    prepare_output_file(out_);
    const Scene scene = generate_scene(scene_.spec());
    const bool text = out_.ends_with(".csv") || out_.ends_with(".txt");
    if (text) {
      write_text_scene(scene, out_);
    } else {
      write_binary_scene(scene, out_);
    }
    fmt::print("wrote {} particles ({}) to {}, checksum {:016x}\n", scene.size(),
               text ? "text" : "binary", out_, scene_checksum(scene));
    return 0;
  }
};

}  // namespace

Subcommand add_scene_command(CLI::App& app) {
  auto command = std::make_shared<SceneCommand>();
  CLI::App* sub = app.add_subcommand("scene", "generate a scene and write it to a file");
  command->scene_.add_to(*sub, false);
  sub->add_option("--out", command->out_, "output file: .csv/.txt text, anything else binary")
      ->required();
  return {sub, [command] { return command->run(); }};
}

}  // namespace contactlab::cli
