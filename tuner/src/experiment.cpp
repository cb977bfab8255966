#include "contactlab/tuner/experiment.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <type_traits>
#include <variant>

#include "contactlab/kernels/detector.hpp"
#include "contactlab/kernels/error.hpp"
#include "contactlab/kernels/rng.hpp"
#include "contactlab/kernels/scene_options.hpp"
#include "contactlab/support/json_reader.hpp"

namespace contactlab::tuner {
namespace {

using nlohmann::json;

// A field of a config: required when no fallback is given; numbers checked against a range.
template <class T>
T number(ObjectIn& object, const std::string& key, std::optional<T> fallback, T low, T high) {
  const std::optional<JsonIn> in = fallback ? object.optional_field(key) : object.field(key);
  if (!in) return *fallback;
  T value{};
  read(*in, value);
  if (value < low || value > high) {
    in->fail("must be in [" + json(low).dump() + ", " + json(high).dump() + "], got " +
             in->value().dump());
  }
  return value;
}

std::string text(ObjectIn& object, const std::string& key, std::optional<std::string> fallback) {
  const std::optional<JsonIn> in = fallback ? object.optional_field(key) : object.field(key);
  if (!in) return *fallback;
  std::string value;
  read(*in, value);
  return value;
}

bool flag(ObjectIn& object, const std::string& key, bool fallback) {
  const std::optional<JsonIn> in = object.optional_field(key);
  bool value = fallback;
  if (in) read(*in, value);
  return value;
}

ExperimentScene parse_scene(const JsonIn& in) {
  ObjectIn o(in);
  ExperimentScene scene;
  scene.file = text(o, "file", "");
  scene.diameter = number<double>(
      o, "diameter", scene.file.empty() ? std::nullopt : std::optional(0.0), 1e-300, 1e300);
  scene.spec.diameter = scene.diameter;
  if (scene.file.empty()) {
    const JsonIn kind = o.field("kind");
    try {
      std::string name;
      read(kind, name);
      scene.spec.kind = parse_scene_kind(name);
    } catch (const SchemaError&) {
      throw;
    } catch (const InputError& e) {
      kind.fail(e.what());
    }
    // The generator's numbers, from the one table the CLI's options are made from too.
    for (const SceneParameter& parameter : kSceneParameters) {
      std::visit(
          [&](const auto& field) {
            using T = std::remove_cvref_t<decltype(scene.spec.*field.member)>;
            T& value = scene.spec.*field.member;
            value = number<T>(o, std::string(parameter.key),
                              parameter.required ? std::nullopt : std::optional<T>(value),
                              field.low, field.high);
          },
          parameter.field);
    }
  }
  scene.name = text(o, "name",
                    scene.file.empty() ? std::string(to_string(scene.spec.kind)) + "-" +
                                             std::to_string(scene.spec.n)
                                       : scene.file);
  o.finish();
  return scene;
}

std::vector<int> parse_chunks(const JsonIn& in) {
  std::vector<int> chunks;
  if (in.value().is_array()) {
    read(in, chunks);
    for (std::size_t i = 0; i < chunks.size(); ++i) {
      if (chunks[i] < 1)
        JsonIn(in.value()[i], in.path() + "[" + std::to_string(i) + "]")
            .fail("chunk sizes must be >= 1");
    }
    return chunks;
  }
  ObjectIn o(in);
  const int from = number<int>(o, "from", std::nullopt, 1, 1'000'000'000);
  const int to = number<int>(o, "to", std::nullopt, 1, 1'000'000'000);
  const int factor = number<int>(o, "factor", 2, 2, 1024);
  o.finish();
  if (to < from) in.fail("'to' must be >= 'from'");
  for (long long k = from; k <= to; k *= factor) chunks.push_back(static_cast<int>(k));
  return chunks;
}

}  // namespace

std::vector<int> powers_of_two(int from, int to) {
  std::vector<int> chunks;
  for (long long k = from; k <= to; k *= 2) chunks.push_back(static_cast<int>(k));
  return chunks;
}

std::vector<Variant> Experiment::variants() const {
  std::vector<Variant> result;
  auto add = [&](const Variant& v) {
    if (std::find(result.begin(), result.end(), v) == result.end()) result.push_back(v);
  };
  for (const std::string& pattern : variant_patterns) {
    const std::size_t at = pattern.find("{k}");
    if (at == std::string::npos) {
      add(parse_variant(pattern));
      continue;
    }
    for (const int k : chunks) {
      std::string text = pattern;
      text.replace(at, 3, std::to_string(k));
      add(parse_variant(text));
    }
  }
  return result;
}

std::string ExperimentPoint::key() const {
  return std::to_string(scene) + "|" + to_string(variant) + "|" + std::to_string(threads);
}

std::vector<ExperimentPoint> experiment_points(const Experiment& experiment, int round) {
  std::vector<ExperimentPoint> points;
  const std::vector<Variant> variants = experiment.variants();
  for (std::size_t s = 0; s < experiment.scenes.size(); ++s) {
    for (const Variant& v : variants) {
      for (const int t : experiment.threads) points.push_back({s, v, t});
    }
  }
  // Fisher-Yates with the project's portable generator: the order is the same everywhere.
  Xoshiro256 rng(experiment.order_seed + static_cast<std::uint64_t>(round));
  for (std::size_t i = points.size(); i > 1; --i) {
    const std::size_t j = static_cast<std::size_t>((rng.next() >> 11) % i);
    std::swap(points[i - 1], points[j]);
  }
  return points;
}

namespace {

Experiment parse_experiment_document(const JsonIn& root) {
  ObjectIn o(root);
  const JsonIn version_in = o.field("schema_version");
  int version = 0;
  read(version_in, version);
  if (version != kExperimentSchemaVersion) {
    version_in.fail("version " + std::to_string(version) + " is not supported (expected " +
                    std::to_string(kExperimentSchemaVersion) + ")");
  }
  Experiment experiment;
  experiment.name = text(o, "name", std::nullopt);
  experiment.description = text(o, "description", "");

  const JsonIn scenes = o.field("scenes");
  if (!scenes.value().is_array() || scenes.value().empty())
    scenes.fail("expected a non-empty array");
  for (std::size_t i = 0; i < scenes.value().size(); ++i) {
    experiment.scenes.push_back(
        parse_scene(JsonIn(scenes.value()[i], scenes.path() + "[" + std::to_string(i) + "]")));
  }

  if (const auto chunks = o.optional_field("chunks")) experiment.chunks = parse_chunks(*chunks);
  const JsonIn variants = o.field("variants");
  if (!variants.value().is_array() || variants.value().empty())
    variants.fail("expected a non-empty array");
  read(variants, experiment.variant_patterns);
  for (std::size_t i = 0; i < experiment.variant_patterns.size(); ++i) {
    const JsonIn at(variants.value()[i], variants.path() + "[" + std::to_string(i) + "]");
    std::string probe = experiment.variant_patterns[i];
    if (const auto k = probe.find("{k}"); k != std::string::npos) {
      if (experiment.chunks.empty()) at.fail("uses {k} but $.chunks is missing");
      probe.replace(k, 3, "1");
    }
    try {
      parse_variant(probe);
    } catch (const InputError& e) {
      at.fail(e.what());
    }
  }

  const JsonIn threads = o.field("threads");
  read(threads, experiment.threads);
  if (experiment.threads.empty()) threads.fail("expected a non-empty array");
  for (std::size_t i = 0; i < experiment.threads.size(); ++i) {
    if (experiment.threads[i] < 0 || experiment.threads[i] > 4096) {
      JsonIn(threads.value()[i], threads.path() + "[" + std::to_string(i) + "]")
          .fail("thread counts must be in [0, 4096] (0 = OpenMP's default, OMP_NUM_THREADS)");
    }
    experiment.threads[i] = resolve_threads(experiment.threads[i]);
  }

  if (const auto repetitions = o.optional_field("repetitions")) {
    ObjectIn r(*repetitions);
    RepetitionPolicy& reps = experiment.repetitions;
    reps.warmup = number<int>(r, "warmup", reps.warmup, 0, 1000);
    reps.repeat = number<int>(r, "min", reps.repeat, 1, 100000);
    reps.max_repeat = number<int>(r, "max", reps.repeat, reps.repeat, 100000);
    const double target = number<double>(r, "target_ci", 0.0, 0.0, 1.0);
    reps.adaptive = target > 0.0;
    if (reps.adaptive) reps.target_relative_half_width = target;
    reps.time_budget_s = number<double>(r, "budget_s", reps.time_budget_s, 0.0, 1e6);
    experiment.rounds = number<int>(r, "rounds", 1, 1, 10000);
    if (experiment.rounds > 1 && reps.adaptive) {
      r.field("rounds").fail(
          "rounds > 1 times a fixed count per visit (\"min\"): drop \"target_ci\" or the rounds");
    }
    r.finish();
  }
  if (const auto measurements = o.optional_field("measurements")) {
    ObjectIn m(*measurements);
    experiment.papi = flag(m, "papi", false);
    experiment.cache_sim = text(m, "cache_sim", "");
    if (!experiment.cache_sim.empty() && experiment.cache_sim != "host" &&
        experiment.cache_sim != "fx10") {
      m.field("cache_sim").fail("expected \"host\" or \"fx10\"");
    }
    experiment.check_contacts = flag(m, "check_contacts", true);
    m.finish();
  }
  experiment.order_seed = number<std::uint64_t>(o, "order_seed", 1, 0, UINT64_MAX);
  o.finish();
  return experiment;
}

}  // namespace

Experiment parse_experiment(const json& document, const std::string& source) {
  try {
    return parse_experiment_document(JsonIn(document, "$"));
  } catch (const SchemaError& e) {
    throw InputError(source + ": " + e.what());
  }
}

Experiment read_experiment(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot open experiment config");
  json document;
  try {
    in >> document;
  } catch (const json::parse_error& e) {
    throw InputError(path + ": not valid JSON (" + std::string(e.what()) + ")");
  }
  return parse_experiment(document, path);
}

}  // namespace contactlab::tuner
