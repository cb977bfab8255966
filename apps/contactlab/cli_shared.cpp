// Scene options and printing helpers shared by the contactlab subcommands.
#include "cli_shared.hpp"

#include <fmt/core.h>

#include <cmath>
#include <optional>
#include <variant>

#include "contactlab/kernels/atomic_file.hpp"
#include "contactlab/kernels/error.hpp"
#include "contactlab/kernels/scene_io.hpp"
#include "contactlab/kernels/scene_options.hpp"

namespace contactlab::cli {

void SceneOptions::add_to(CLI::App& app, bool with_input) {
  if (with_input) app.add_option("--input", input_, "particle file (text x,y,z[,d] or binary)");
  app.add_option(with_input ? "--scene" : "--kind", kind_,
                 "generated scene: uniform, clustered, blobs, polydisperse, core");
  app.add_option("--diameter,-D", diameter_, "particle diameter D (contact distance)")
      ->each([this](const std::string&) { diameter_given_ = true; });
  // The generator's numbers: the same table gives the experiment configs their keys.
  for (const SceneParameter& parameter : kSceneParameters) {
    std::visit(
        [&](const auto& field) {
          app.add_option(std::string(parameter.option), spec_.*field.member,
                         std::string(parameter.help));
        },
        parameter.field);
  }
  app.add_option("--box", box_, "box xmin,ymin,zmin,xmax,ymax,zmax (default unit cube)");
}

SceneSpec SceneOptions::spec() const {
  SceneSpec s = spec_;
  s.kind = parse_scene_kind(kind_);
  s.diameter = diameter_;
  if (!box_.empty()) s.box = parse_box(box_);
  return s;
}

void SceneOptions::require_diameter() const {
  if (!diameter_given_) throw InputError("--diameter is required");
  if (!(diameter_ > 0.0) || !std::isfinite(diameter_)) {
    throw InputError(fmt::format("--diameter must be a positive finite number, got {}", diameter_));
  }
}

std::pair<Scene, tuner::SceneRecord> SceneOptions::load() const {
  if (!input_.empty()) {
    const Box b = box_.empty() ? Box{} : parse_box(box_);
    Scene scene = read_scene(input_, b);
    if (!scene.has_diameters()) require_diameter();
    tuner::SceneRecord record = tuner::describe_file_scene(input_, scene, diameter_);
    return {std::move(scene), std::move(record)};
  }
  require_diameter();
  const SceneSpec s = spec();
  Scene scene = generate_scene(s);
  tuner::SceneRecord record = tuner::describe_generated_scene(s, scene);
  return {std::move(scene), std::move(record)};
}

void DemStateOptions::add_to(CLI::App& app) {
  app.add_option("config", config, "DEM config")->required();
  app.add_option("--restart", restart,
                 "plan on this checkpoint of the config (default: its start)");
  app.add_option("--axis", axis, "slab axis x, y or z (default: the longest)");
}

void NetworkOptions::add_to(CLI::App& app) {
  app.add_option("--latency", latency_s, "network latency per message [s] (1.5e-6)");
  app.add_option("--bandwidth", bandwidth, "network bandwidth [bytes/s] (5e9)");
  app.add_option("--network-source", source, "where the network figures come from");
}

void NetworkOptions::check() const {
  if (!(latency_s >= 0.0) || !(bandwidth > 0.0)) {
    throw InputError("--latency must be >= 0 and --bandwidth > 0");
  }
}

void MemoryOptions::add_to(CLI::App& app, const std::string& prices) {
  app.add_option("--machine", machine_file,
                 "also price " + prices +
                     " by their bytes at the bandwidth of this machine file (`contactlab probe "
                     "--json`)");
  app.add_option("--bandwidth-ceiling", ceiling_gb_s,
                 "--machine: the bandwidth the probed curve saturates towards beyond the "
                 "machine's cores, GB/s (default: the last probed value)");
  app.add_option("--ceiling-source", ceiling_source,
                 "where the ceiling comes from (required with --bandwidth-ceiling)");
}

std::optional<tuner::MemorySystem> MemoryOptions::load() const {
  if (ceiling_gb_s != 0.0) {
    if (machine_file.empty()) {
      throw InputError("--bandwidth-ceiling extends a machine file: give --machine");
    }
    if (!(ceiling_gb_s > 0.0)) throw InputError("--bandwidth-ceiling must be > 0 (GB/s)");
    if (ceiling_source.empty()) {
      throw InputError("--bandwidth-ceiling needs --ceiling-source (where the figure comes from)");
    }
  }
  if (machine_file.empty()) return std::nullopt;
  return tuner::MemorySystem{machine_file, tuner::read_machine_file(machine_file),
                             ceiling_gb_s * 1e9, ceiling_source};
}

std::vector<std::string> split_list(const std::string& text) {
  std::vector<std::string> items;
  std::size_t pos = 0;
  while (pos <= text.size()) {
    const auto comma = text.find(',', pos);
    std::string item =
        text.substr(pos, comma == std::string::npos ? std::string::npos : comma - pos);
    if (item.empty()) throw InputError("--papi-events: empty event name in '" + text + "'");
    items.push_back(std::move(item));
    if (comma == std::string::npos) break;
    pos = comma + 1;
  }
  return items;
}

std::vector<int> int_list(const std::string& text, const char* option) {
  std::vector<int> values;
  for (const std::string& item : split_list(text)) {
    std::size_t used = 0;
    int value = 0;
    try {
      value = std::stoi(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != item.size() || value < 1) {
      throw InputError(fmt::format("{}: '{}' is not a whole number >= 1", option, item));
    }
    values.push_back(value);
  }
  return values;
}

namespace {

std::string percent(const std::optional<double>& value) {
  return value ? fmt::format("{:.3f}%", *value) : std::string("n/a");
}

}  // namespace

void write_json(const std::string& path, const nlohmann::json& doc) {
  write_file_atomically(path, [&](std::ostream& out) { out << doc.dump(2) << '\n'; });
  fmt::print("wrote {}\n", path);
}

void print_counters(const tuner::CounterRecord& c) {
  if (!c.available) {
    fmt::print("counters {}: unavailable: {}\n", c.source, c.reason);
    return;
  }
  fmt::print("counters {}: L1 miss {}  L2 miss {}{}\n", c.source, percent(c.l1_miss_percent),
             percent(c.l2_miss_percent), c.simulation ? "  (simulated; an approximation)" : "");
  for (const auto& e : c.events) {
    std::string threads;
    for (const auto v : e.per_thread) threads += (threads.empty() ? "" : ", ") + std::to_string(v);
    fmt::print("  {:<28} {:>16}{}\n", e.name, e.total,
               threads.empty() ? "" : "  per thread [" + threads + "]");
  }
}

}  // namespace contactlab::cli
