// contactlab: the command-line program. Parses options, calls the libraries, prints.
#include <fmt/core.h>
#include <omp.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>

#include "contactlab/kernels/atomic_file.hpp"
#include "contactlab/kernels/build_info.hpp"
#include "contactlab/kernels/detector.hpp"
#include "contactlab/kernels/error.hpp"
#include "contactlab/kernels/scene_generate.hpp"
#include "contactlab/kernels/scene_io.hpp"

namespace cl = contactlab;
using nlohmann::json;

namespace {

// Where the particles come from: a file, or a generator spec.
struct SceneOptions {
  std::string input;
  std::string kind = "clustered";
  std::uint64_t n = 100'000;
  double diameter = 0.0;
  bool diameter_given = false;
  std::uint64_t seed = 1;
  std::string box;
  double core = cl::SceneSpec{}.core;
  double background = cl::SceneSpec{}.background;
  int blobs = cl::SceneSpec{}.blob_count;
  double size_ratio = cl::SceneSpec{}.size_ratio;

  void add_to(CLI::App& app, bool with_input) {
    if (with_input) app.add_option("--input", input, "particle file (text x,y,z[,d] or binary)");
    app.add_option(with_input ? "--scene" : "--kind", kind,
                   "generated scene: uniform, clustered, blobs, polydisperse");
    app.add_option("--n", n, "number of particles of a generated scene");
    app.add_option("--diameter,-D", diameter, "particle diameter D (contact distance)")
        ->each([this](const std::string&) { diameter_given = true; });
    app.add_option("--seed", seed, "generator seed");
    app.add_option("--box", box, "box xmin,ymin,zmin,xmax,ymax,zmax (default unit cube)");
    app.add_option("--core", core, "clustered/blobs: relative core radius c (docs/scenes.md)");
    app.add_option("--background", background, "clustered/blobs: fraction spread uniformly");
    app.add_option("--blobs", blobs, "blobs: number of clusters");
    app.add_option("--size-ratio", size_ratio, "polydisperse: largest / smallest diameter");
  }

  cl::SceneSpec spec() const {
    cl::SceneSpec s;
    s.kind = cl::parse_scene_kind(kind);
    s.n = n;
    s.diameter = diameter;
    s.seed = seed;
    if (!box.empty()) s.box = cl::parse_box(box);
    s.core = core;
    s.background = background;
    s.blob_count = blobs;
    s.size_ratio = size_ratio;
    return s;
  }

  void require_diameter() const {
    if (!diameter_given) throw cl::InputError("--diameter is required");
    if (!(diameter > 0.0) || !std::isfinite(diameter)) {
      throw cl::InputError(fmt::format("--diameter must be a positive finite number, got {}", diameter));
    }
  }

  // The scene and its description for result files.
  std::pair<cl::Scene, json> load() const {
    if (!input.empty()) {
      const cl::Box b = box.empty() ? cl::Box{} : cl::parse_box(box);
      cl::Scene scene = cl::read_scene(input, b);
      if (!scene.has_diameters()) require_diameter();
      json description = {{"kind", "file"},
                          {"path", input},
                          {"n", scene.size()},
                          {"diameter", scene.has_diameters() ? json(nullptr) : json(diameter)},
                          {"checksum", fmt::format("{:016x}", cl::scene_checksum(scene))}};
      return {std::move(scene), description};
    }
    require_diameter();
    const cl::SceneSpec s = spec();
    cl::Scene scene = cl::generate_scene(s);
    json description = {{"kind", std::string(cl::to_string(s.kind))},
                        {"n", s.n},
                        {"diameter", s.diameter},
                        {"seed", s.seed},
                        {"core", s.core},
                        {"background", s.background},
                        {"checksum", fmt::format("{:016x}", cl::scene_checksum(scene))}};
    return {std::move(scene), description};
  }
};

double median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const std::size_t m = values.size() / 2;
  return values.size() % 2 ? values[m] : 0.5 * (values[m - 1] + values[m]);
}

struct Repeated {
  std::vector<cl::DetectRun> runs;
  double median_setup() const { return median(collect(&cl::DetectRun::setup_s)); }
  double median_detect() const { return median(collect(&cl::DetectRun::detect_s)); }
  double median_total() const {
    std::vector<double> totals;
    for (const auto& r : runs) totals.push_back(r.total_s());
    return median(totals);
  }
  std::vector<double> collect(double cl::DetectRun::*field) const {
    std::vector<double> values;
    for (const auto& r : runs) values.push_back(r.*field);
    return values;
  }
};

Repeated repeat_detection(cl::ContactDetector& detector, const cl::Scene& scene,
                          const cl::DetectOptions& options, int warmup, int repeat) {
  for (int i = 0; i < warmup; ++i) detector.run(scene, options);
  Repeated result;
  for (int i = 0; i < repeat; ++i) result.runs.push_back(detector.run(scene, options));
  return result;
}

json build_json() {
  const auto& b = cl::build_info();
  return {{"version", b.version},       {"compiler", b.compiler},   {"flags", b.flags},
          {"build_type", b.build_type}, {"native", b.native},       {"git_commit", b.git_commit},
          {"git_dirty", b.git_dirty}};
}

int command_scene(const SceneOptions& options, const std::string& out) {
  options.require_diameter();
  cl::check_writable(out);
  const cl::Scene scene = cl::generate_scene(options.spec());
  const bool text = out.ends_with(".csv") || out.ends_with(".txt");
  if (text) {
    cl::write_text_scene(scene, out);
  } else {
    cl::write_binary_scene(scene, out);
  }
  fmt::print("wrote {} particles ({}) to {}, checksum {:016x}\n", scene.size(),
             text ? "text" : "binary", out, cl::scene_checksum(scene));
  return 0;
}

struct DetectCommand {
  std::string variant = "particle/sorted/full/static,200";
  int threads = 0;
  int repeat = 3;
  int warmup = 1;
  std::string contacts_out;
  std::string json_out;
};

int command_detect(const SceneOptions& scene_options, const DetectCommand& command,
                   const std::string& command_line) {
  if (command.repeat < 1) throw cl::InputError("--repeat must be >= 1");
  if (command.warmup < 0) throw cl::InputError("--warmup must be >= 0");
  if (command.threads < 0) throw cl::InputError("--threads must be >= 0");
  const cl::Variant variant = cl::parse_variant(command.variant);
  if (!command.contacts_out.empty()) cl::check_writable(command.contacts_out);
  if (!command.json_out.empty()) cl::check_writable(command.json_out);
  auto [scene, scene_json] = scene_options.load();

  cl::DetectOptions options;
  options.variant = variant;
  options.diameter = scene_options.diameter;
  options.threads = command.threads;
  cl::ContactDetector detector;
  const Repeated result = repeat_detection(detector, scene, options, command.warmup, command.repeat);
  const cl::DetectRun& last = result.runs.back();

  fmt::print("variant {}  threads {}  N {}  grid {}x{}x{}  max occupancy {}\n", cl::to_string(variant),
             last.threads, scene.size(), last.grid_dims[0], last.grid_dims[1], last.grid_dims[2],
             last.max_cell_occupancy);
  fmt::print("T_s {:.6f} s  T_c {:.6f} s  T_ALL {:.6f} s  (median of {})\n", result.median_setup(),
             result.median_detect(), result.median_total(), command.repeat);
  fmt::print("candidate tests {}  contacts {}\n", last.candidate_tests, last.contact_pairs);

  if (!command.contacts_out.empty()) cl::write_pairs_csv(detector.canonical_contacts(), command.contacts_out);
  if (!command.json_out.empty()) {
    json record = {
        {"variant", cl::to_string(variant)},
        {"scene", scene_json},
        {"threads", last.threads},
        {"samples",
         {{"setup_s", result.collect(&cl::DetectRun::setup_s)},
          {"detect_s", result.collect(&cl::DetectRun::detect_s)}}},
        {"median", {{"setup_s", result.median_setup()}, {"detect_s", result.median_detect()},
                    {"total_s", result.median_total()}}},
        {"thread_busy_s", last.thread_busy_s},
        {"candidate_tests", last.candidate_tests},
        {"contact_pairs", last.contact_pairs},
        {"max_cell_occupancy", last.max_cell_occupancy},
        {"grid", last.grid_dims},
        {"build", build_json()},
        {"command", command_line},
    };
    cl::write_file_atomically(command.json_out, [&](std::ostream& out) { out << record.dump(2) << '\n'; });
  }
  return 0;
}

int command_variants() {
  fmt::print("Variants are written loop/order/stencil/schedule (loop/order/schedule = full stencil).\n");
  fmt::print("  loop      cell | particle            parallel over grid cells (paper Fig. 4) or particles (Fig. 5)\n");
  fmt::print("  order     unsorted | sorted | morton input order, grouped by cell (paper), or by cell in Morton order\n");
  fmt::print("  stencil   full | half                27 cells, or own + 13 forward cells (each pair tested once)\n");
  fmt::print("  schedule  static | static,k | dynamic,k | guided,k   (k >= 1; static = block partition)\n\n");
  fmt::print("The paper's configurations:\n");
  for (const auto& v : cl::paper_variants()) fmt::print("  {}\n", cl::to_string(v));
  fmt::print("\nEvery loop/order/stencil (schedules as above, any k):\n");
  cl::VariantSpace space = cl::all_variants({});
  for (const auto& v : cl::enumerate(space)) fmt::print("  {}\n", cl::to_string(v));
  return 0;
}

// The main job: every paper variant (and ours) on a small clustered scene, at 1 thread and at
// every core, as a table like the paper's.
int command_demo(SceneOptions scene_options, int repeat) {
  if (!scene_options.diameter_given) {
    scene_options.diameter = 1.0 / 200.0;
    scene_options.diameter_given = true;
  }
  auto [scene, scene_json] = scene_options.load();
  const int cores = omp_get_num_procs();
  std::vector<cl::Variant> variants = cl::paper_variants();
  variants.push_back(cl::parse_variant("particle/sorted/half/static,200"));
  variants.push_back(cl::parse_variant("particle/morton/half/static,200"));
  fmt::print("Clustered scene: N = {}, D = {}, seed {}; {} cores; median of {} runs\n\n", scene.size(),
             scene_options.diameter, scene_options.seed, cores, repeat);
  fmt::print("{:<36} {:>7} {:>10} {:>10} {:>10} {:>8} {:>12}\n", "variant", "threads", "T_s [s]",
             "T_c [s]", "T_ALL [s]", "speedup", "contacts");
  cl::ContactDetector detector;
  std::optional<cl::ContactList> reference;
  bool all_equal = true;
  for (const auto& variant : variants) {
    double serial = 0.0;
    for (const int threads : {1, cores}) {
      if (threads == cores && cores == 1) break;
      cl::DetectOptions options{variant, scene_options.diameter, threads, nullptr};
      const Repeated r = repeat_detection(detector, scene, options, 1, repeat);
      if (threads == 1) serial = r.median_total();
      fmt::print("{:<36} {:>7} {:>10.4f} {:>10.4f} {:>10.4f} {:>8.2f} {:>12}\n", cl::to_string(variant),
                 threads, r.median_setup(), r.median_detect(), r.median_total(),
                 serial / r.median_total(), r.runs.back().contact_pairs);
      cl::ContactList contacts = detector.canonical_contacts();
      if (!reference) {
        reference = std::move(contacts);
      } else if (contacts != *reference) {
        all_equal = false;
      }
    }
  }
  fmt::print("\nContact lists identical across all variants and thread counts: {}\n",
             all_equal ? "yes" : "NO");
  return all_equal ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"contactlab: particle contact detection — variants, measurement, tuning"};
  app.require_subcommand(1);
  std::string command_line;
  for (int i = 0; i < argc; ++i) command_line += (i ? " " : "") + std::string(argv[i]);

  SceneOptions scene_options;
  std::string scene_out;
  CLI::App* scene = app.add_subcommand("scene", "generate a scene and write it to a file");
  scene_options.add_to(*scene, false);
  scene->add_option("--out", scene_out, "output file: .csv/.txt text, anything else binary")->required();

  SceneOptions detect_scene;
  DetectCommand detect_command;
  CLI::App* detect = app.add_subcommand("detect", "detect contacts with one variant");
  detect_scene.add_to(*detect, true);
  detect->add_option("--variant", detect_command.variant, "loop/order[/stencil]/schedule");
  detect->add_option("--threads", detect_command.threads, "OpenMP threads (0 = all)");
  detect->add_option("--repeat", detect_command.repeat, "timed repetitions");
  detect->add_option("--warmup", detect_command.warmup, "untimed runs first");
  detect->add_option("--contacts-out", detect_command.contacts_out, "CSV of contacts i,j (i < j)");
  detect->add_option("--json", detect_command.json_out, "result record (JSON)");

  app.add_subcommand("variants", "list every variant and its parameters");

  SceneOptions demo_scene;
  int demo_repeat = 3;
  CLI::App* demo = app.add_subcommand("demo", "time the paper's variants on a small clustered scene");
  demo_scene.add_to(*demo, false);
  demo->add_option("--repeat", demo_repeat, "timed repetitions");

  try {
    app.parse(argc, argv);
    if (*scene) return command_scene(scene_options, scene_out);
    if (*detect) return command_detect(detect_scene, detect_command, command_line);
    if (*demo) return command_demo(demo_scene, demo_repeat);
    return command_variants();
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const cl::InputError& e) {
    fmt::print(stderr, "contactlab: error: {}\n", e.what());
    return 2;
  } catch (const std::bad_alloc&) {
    fmt::print(stderr, "contactlab: error: out of memory\n");
    return 3;
  }
}
