// `contactlab demo`: every paper variant (and ours) on a small clustered scene, at 1 thread and
// at every core, as a table like the paper's; checks that all contact lists agree.
#include <fmt/core.h>
#include <omp.h>

#include <memory>
#include <optional>

#include "cli_shared.hpp"
#include "contactlab/kernels/detector.hpp"
#include "contactlab/kernels/error.hpp"
#include "contactlab/tuner/measure.hpp"

namespace contactlab::cli {
namespace {

namespace tn = contactlab::tuner;

struct DemoCommand {
  SceneOptions scene_;
  int repeat_ = 3;

  int run() const;
};

int DemoCommand::run() const {
  if (repeat_ < 1) throw InputError("--repeat must be >= 1");
  SceneOptions scene_options = scene_;
  if (!scene_options.diameter_given_) {
    scene_options.diameter_ = 1.0 / 200.0;
    scene_options.diameter_given_ = true;
  }
  const double diameter = scene_options.diameter_;
  auto [scene, scene_record] = scene_options.load();
  const int cores = omp_get_num_procs();
  std::vector<Variant> variants = paper_variants();
  variants.push_back(parse_variant("particle/sorted/half/static,200"));
  variants.push_back(parse_variant("particle/morton/half/static,200"));
  fmt::print("Clustered scene: N = {}, D = {}, seed {}; {} cores; median of {} runs\n\n",
             scene.size(), diameter, scene_options.spec_.seed, cores, repeat_);
  fmt::print("{:<36} {:>7} {:>10} {:>10} {:>10} {:>8} {:>12}\n", "variant", "threads", "T_s [s]",
             "T_c [s]", "T_ALL [s]", "speedup", "contacts");
  ContactDetector detector;
  std::optional<ContactList> reference;
  bool all_equal = true;
  for (const auto& variant : variants) {
    double serial = 0.0;
    for (const int threads : {1, cores}) {
      if (threads == cores && cores == 1) break;
      DetectOptions options{variant, diameter, threads, nullptr};
      tn::MeasureOptions measure;
      measure.repetition.warmup = 1;
      measure.repetition.repeat = repeat_;
      const tn::RunRecord r =
          tn::measure_detection(detector, scene, scene_record, options, measure);
      const tn::RunAggregates& a = *r.aggregates;
      if (threads == 1) serial = a.total_s.median;
      fmt::print("{:<36} {:>7} {:>10.4f} {:>10.4f} {:>10.4f} {:>8.2f} {:>12}\n", to_string(variant),
                 threads, a.setup_s.median, a.detect_s.median, a.total_s.median,
                 serial / a.total_s.median, r.work->contact_pairs);
      ContactList contacts = detector.canonical_contacts();
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

Subcommand add_demo_command(CLI::App& app) {
  auto command = std::make_shared<DemoCommand>();
  CLI::App* sub =
      app.add_subcommand("demo", "time the paper's variants on a small clustered scene");
  command->scene_.add_to(*sub, false);
  sub->add_option("--repeat", command->repeat_, "timed repetitions");
  return {sub, [command] { return command->run(); }};
}

}  // namespace contactlab::cli
