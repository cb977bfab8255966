#include "contactlab/tuner/experiment.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>

#include "contactlab/kernels/error.hpp"
#include "contactlab/kernels/rng.hpp"

namespace contactlab::tuner {
namespace {

using nlohmann::json;

// Reads an object field by field; anything left unread at the end is an unknown key.
class ObjectReader {
 public:
  ObjectReader(const json& object, std::string path, const std::string& source)
      : object_(object), path_(std::move(path)), source_(source) {
    if (!object.is_object()) fail(path_, "expected an object");
  }

  [[noreturn]] void fail(const std::string& path, const std::string& problem) const {
    throw InputError(source_ + ": " + path + ": " + problem);
  }
  std::string path_of(const std::string& key) const { return path_ + "." + key; }

  const json* find(const std::string& key) {
    seen_.insert(key);
    const auto it = object_.find(key);
    return it == object_.end() ? nullptr : &*it;
  }
  const json& require(const std::string& key) {
    const json* value = find(key);
    if (!value) fail(path_of(key), "missing");
    return *value;
  }

  template <class T>
  T number(const std::string& key, T fallback, T low, T high, bool required = false) {
    const json* value = required ? &require(key) : find(key);
    if (!value) return fallback;
    if (!value->is_number()) fail(path_of(key), "expected a number");
    if constexpr (std::is_integral_v<T>) {
      if (!value->is_number_integer()) fail(path_of(key), "expected an integer");
    }
    const double as_double = value->get<double>();
    if (!std::isfinite(as_double) || as_double < double(low) || as_double > double(high)) {
      fail(path_of(key), "must be in [" + json(low).dump() + ", " + json(high).dump() + "], got " +
                             value->dump());
    }
    return value->get<T>();
  }
  std::string text(const std::string& key, const std::string& fallback, bool required = false) {
    const json* value = required ? &require(key) : find(key);
    if (!value) return fallback;
    if (!value->is_string()) fail(path_of(key), "expected a string");
    return value->get<std::string>();
  }
  bool flag(const std::string& key, bool fallback) {
    const json* value = find(key);
    if (!value) return fallback;
    if (!value->is_boolean()) fail(path_of(key), "expected true or false");
    return value->get<bool>();
  }

  void finish() const {
    for (auto it = object_.begin(); it != object_.end(); ++it) {
      if (!seen_.count(it.key())) fail(path_of(it.key()), "unknown key");
    }
  }

 private:
  const json& object_;
  std::string path_;
  const std::string& source_;
  std::set<std::string> seen_;
};

ExperimentScene parse_scene(const json& value, const std::string& path, const std::string& source) {
  ObjectReader reader(value, path, source);
  ExperimentScene scene;
  scene.file = reader.text("file", "");
  scene.diameter = reader.number<double>("diameter", 0.0, 1e-300, 1e300, scene.file.empty());
  scene.spec.diameter = scene.diameter;
  if (scene.file.empty()) {
    const std::string kind = reader.text("kind", "", true);
    try {
      scene.spec.kind = parse_scene_kind(kind);
    } catch (const InputError& e) {
      reader.fail(reader.path_of("kind"), e.what());
    }
    scene.spec.n = reader.number<std::uint64_t>("n", 0, 0, UINT32_MAX - 1, true);
    scene.spec.seed = reader.number<std::uint64_t>("seed", 1, 0, UINT64_MAX);
    scene.spec.core = reader.number<double>("core", scene.spec.core, 1e-6, 100.0);
    scene.spec.background = reader.number<double>("background", scene.spec.background, 0.0, 1.0);
    scene.spec.blob_count = reader.number<int>("blobs", scene.spec.blob_count, 1, 1'000'000);
    scene.spec.blob_radius =
        reader.number<double>("blob_radius", scene.spec.blob_radius, 1e-6, 0.5);
    scene.spec.size_ratio = reader.number<double>("size_ratio", scene.spec.size_ratio, 1.0, 1e6);
  }
  scene.name = reader.text("name", scene.file.empty() ? std::string(to_string(scene.spec.kind)) +
                                                            "-" + std::to_string(scene.spec.n)
                                                      : scene.file);
  reader.finish();
  return scene;
}

std::vector<int> parse_chunks(const json& value, const std::string& path,
                              const std::string& source) {
  if (value.is_array()) {
    std::vector<int> chunks;
    for (std::size_t i = 0; i < value.size(); ++i) {
      const json& k = value[i];
      if (!k.is_number_integer() || k.get<long long>() < 1 || k.get<long long>() > 1'000'000'000) {
        throw InputError(source + ": " + path + "[" + std::to_string(i) +
                         "]: chunk sizes must be integers >= 1");
      }
      chunks.push_back(k.get<int>());
    }
    return chunks;
  }
  ObjectReader reader(value, path, source);
  const int from = reader.number<int>("from", 1, 1, 1'000'000'000, true);
  const int to = reader.number<int>("to", 1, 1, 1'000'000'000, true);
  const int factor = reader.number<int>("factor", 2, 2, 1024);
  reader.finish();
  if (to < from) reader.fail(path, "'to' must be >= 'from'");
  std::vector<int> chunks;
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

std::vector<ExperimentPoint> experiment_points(const Experiment& experiment) {
  std::vector<ExperimentPoint> points;
  const std::vector<Variant> variants = experiment.variants();
  for (std::size_t s = 0; s < experiment.scenes.size(); ++s) {
    for (const Variant& v : variants) {
      for (const int t : experiment.threads) points.push_back({s, v, t});
    }
  }
  // Fisher-Yates with the project's portable generator: the order is the same everywhere.
  Xoshiro256 rng(experiment.order_seed);
  for (std::size_t i = points.size(); i > 1; --i) {
    const std::size_t j = static_cast<std::size_t>((rng.next() >> 11) % i);
    std::swap(points[i - 1], points[j]);
  }
  return points;
}

Experiment parse_experiment(const json& document, const std::string& source) {
  ObjectReader reader(document, "$", source);
  const int version = reader.number<int>("schema_version", 0, 0, 1'000'000, true);
  if (version != kExperimentSchemaVersion) {
    reader.fail("$.schema_version", "version " + std::to_string(version) +
                                        " is not supported (expected " +
                                        std::to_string(kExperimentSchemaVersion) + ")");
  }
  Experiment experiment;
  experiment.name = reader.text("name", "", true);
  experiment.description = reader.text("description", "");

  const json& scenes = reader.require("scenes");
  if (!scenes.is_array() || scenes.empty()) reader.fail("$.scenes", "expected a non-empty array");
  for (std::size_t i = 0; i < scenes.size(); ++i) {
    experiment.scenes.push_back(
        parse_scene(scenes[i], "$.scenes[" + std::to_string(i) + "]", source));
  }

  if (const json* chunks = reader.find("chunks"))
    experiment.chunks = parse_chunks(*chunks, "$.chunks", source);
  const json& variants = reader.require("variants");
  if (!variants.is_array() || variants.empty())
    reader.fail("$.variants", "expected a non-empty array");
  for (std::size_t i = 0; i < variants.size(); ++i) {
    const std::string path = "$.variants[" + std::to_string(i) + "]";
    if (!variants[i].is_string()) reader.fail(path, "expected a variant string");
    const std::string pattern = variants[i].get<std::string>();
    if (pattern.find("{k}") != std::string::npos && experiment.chunks.empty()) {
      reader.fail(path, "uses {k} but $.chunks is missing");
    }
    try {
      std::string probe = pattern;
      if (const auto at = probe.find("{k}"); at != std::string::npos) probe.replace(at, 3, "1");
      parse_variant(probe);
    } catch (const InputError& e) {
      reader.fail(path, e.what());
    }
    experiment.variant_patterns.push_back(pattern);
  }

  const json& threads = reader.require("threads");
  if (!threads.is_array() || threads.empty())
    reader.fail("$.threads", "expected a non-empty array");
  for (std::size_t i = 0; i < threads.size(); ++i) {
    if (!threads[i].is_number_integer() || threads[i].get<long long>() < 1 ||
        threads[i].get<long long>() > 4096) {
      reader.fail("$.threads[" + std::to_string(i) + "]",
                  "thread counts must be integers in [1, 4096]");
    }
    experiment.threads.push_back(threads[i].get<int>());
  }

  if (const json* repetitions = reader.find("repetitions")) {
    ObjectReader r(*repetitions, "$.repetitions", source);
    auto& reps = experiment.repetitions;
    reps.warmup = r.number<int>("warmup", reps.warmup, 0, 1000);
    reps.repeat = r.number<int>("min", reps.repeat, 1, 100000);
    reps.max_repeat = r.number<int>("max", reps.repeat, reps.repeat, 100000);
    const double target = r.number<double>("target_ci", 0.0, 0.0, 1.0);
    reps.adaptive = target > 0.0;
    if (reps.adaptive) reps.target_relative_half_width = target;
    reps.time_budget_s = r.number<double>("budget_s", reps.time_budget_s, 0.0, 1e6);
    r.finish();
  }
  if (const json* measurements = reader.find("measurements")) {
    ObjectReader m(*measurements, "$.measurements", source);
    experiment.papi = m.flag("papi", false);
    experiment.cache_sim = m.text("cache_sim", "");
    if (!experiment.cache_sim.empty() && experiment.cache_sim != "host" &&
        experiment.cache_sim != "fx10") {
      m.fail("$.measurements.cache_sim", "expected \"host\" or \"fx10\"");
    }
    experiment.check_contacts = m.flag("check_contacts", true);
    m.finish();
  }
  experiment.order_seed = reader.number<std::uint64_t>("order_seed", 1, 0, UINT64_MAX);
  reader.finish();
  return experiment;
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
