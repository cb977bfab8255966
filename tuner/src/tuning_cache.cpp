// The tuning cache (tune.hpp, docs/tuning.md): its records are read strictly and written through
// field tables (field_table.hpp), like result files; the cost model's constants through
// kMachineCostFields, the one list that calibration also uses.
#include <fmt/core.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <tuple>

#include "contactlab/kernels/atomic_file.hpp"
#include "contactlab/kernels/error.hpp"
#include "contactlab/tuner/context.hpp"
#include "contactlab/tuner/field_table.hpp"
#include "contactlab/tuner/tune.hpp"

namespace contactlab::tuner {
namespace {

using nlohmann::json;

constexpr int kCacheSchemaVersion = 1;
// A calibration stored by a cost model with other constants (another kCostModelVersion) is a
// cache miss.
// 3, 4: the output term (output_cost.hpp) by bytes, by degree; 5: the balanced weighing's own
// constants; 6: the half stencil's exchange (OutputCost::exchange).
constexpr int kCostModelVersion = 6;

std::string machine_key() {
  const MachineInfo& m = machine_info();
  const BuildRecord b = build_record();
  return fmt::format("{}|{} cpus|{}|{}", m.cpu_model, m.pus, b.flags, b.git_commit);
}

std::string choice_key(const SceneRecord& scene, double diameter, int threads,
                       const std::string& setting) {
  std::string key =
      fmt::format("{}|{}|{}|{:.17g}|{}", machine_key(), scene.checksum, scene.n, diameter, threads);
  if (!setting.empty()) key += "|" + setting;
  return key;
}

struct CachedCalibration {
  int cost_model_version = kCostModelVersion;
  double seconds = 0.0;
  int threads = 0;
  std::map<std::string, StructureCosts> structures;
};

struct CachedChoice {
  std::string variant;
  double detect_s = 0.0;
};

// A calibration as the cache stores it, and back (the cache's copy says where it came from).
CachedCalibration to_cached(const Calibration& c) {
  return {kCostModelVersion, c.seconds, c.threads, c.structures};
}
Calibration from_cached(const CachedCalibration& cached) {
  Calibration c;
  c.source = "cache";
  c.seconds = cached.seconds;
  c.threads = cached.threads;
  c.structures = cached.structures;
  return c;
}

// Calibrations stay raw JSON in the document: those of other machines and builds, or of another
// cost model (other constants), are kept as they are and never read; only this machine's entry
// of the current cost model is read strictly, when it is looked up.
struct CacheDocument {
  int schema_version = kCacheSchemaVersion;
  std::map<std::string, json> calibrations;
  std::map<std::string, CachedChoice> choices;
};

void check_cache_version(const JsonIn& at, const int& version) {
  if (version != kCacheSchemaVersion) at.fail(fmt::format("version {} is not supported", version));
}

}  // namespace

template <>
struct FieldTable<MachineCosts> {
  // The loop's constants (fitted together), then the balanced schedule's weighing (fitted apart,
  // -1 where nothing weighed: a one-thread calibration).
  static constexpr auto kFields = std::tuple{
      field_list(kMachineCostFields),
      field("seconds_per_weighed_iteration", &MachineCosts::seconds_per_weighed_iteration),
      field("seconds_per_weighed_build", &MachineCosts::seconds_per_weighed_build)};
};

template <>
struct FieldTable<OutputCost> {
  using T = OutputCost;
  static constexpr auto kFields =
      std::tuple{field("threads", &T::threads),
                 field("low_degree", &T::low_degree),
                 field("low_seconds_per_entry", &T::low_seconds_per_entry),
                 field("high_degree", &T::high_degree),
                 field("high_seconds_per_entry", &T::high_seconds_per_entry),
                 field("exchange", &T::exchange).may_be_absent()};
};

template <>
struct FieldTable<StructureCosts> {
  using T = StructureCosts;
  static constexpr auto kFields =
      std::tuple{field("costs", &T::costs), field("rms_relative_error", &T::rms_relative_error),
                 field("runs", &T::runs), field("output", &T::output)};
};

template <>
struct FieldTable<CachedCalibration> {
  using T = CachedCalibration;
  static constexpr auto kFields =
      std::tuple{field("cost_model_version", &T::cost_model_version), field("seconds", &T::seconds),
                 field("threads", &T::threads), field("structures", &T::structures)};
};

template <>
struct FieldTable<CachedChoice> {
  using T = CachedChoice;
  static constexpr auto kFields =
      std::tuple{field("variant", &T::variant), field("detect_s", &T::detect_s)};
};

template <>
struct FieldTable<CacheDocument> {
  using T = CacheDocument;
  static constexpr auto kFields =
      std::tuple{field("schema_version", &T::schema_version).checked(&check_cache_version),
                 field("calibrations", &T::calibrations), field("choices", &T::choices)};
};

namespace {

// One entry of the cache file, read strictly; errors name the file and the entry.
template <class T>
T read_entry(const std::string& file, const json& value, const std::string& path) {
  T out;
  try {
    read(JsonIn(value, path), out);
  } catch (const SchemaError& e) {
    throw InputError(file + ": not a contactlab tuning cache (schema_version 1): " + e.what() +
                     "; delete it to start a new one");
  }
  return out;
}

}  // namespace

std::string TuningCache::default_path() {
  namespace fs = std::filesystem;
  if (const char* dir = std::getenv("CONTACTLAB_CACHE_DIR"); dir && *dir)
    return (fs::path(dir) / "tuning.json").string();
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg && *xdg) {
    return (fs::path(xdg) / "contactlab" / "tuning.json").string();
  }
  const char* home = std::getenv("HOME");
  return (fs::path(home && *home ? home : ".") / ".cache" / "contactlab" / "tuning.json").string();
}

TuningCache::TuningCache(std::string path) : path_(std::move(path)) {}

json TuningCache::load() const {
  std::ifstream in(path_);
  if (!in) return to_json_value(CacheDocument{});
  json document;
  try {
    document = json::parse(in);
  } catch (const json::exception& e) {
    throw InputError(path_ + ": tuning cache is not valid JSON (" + std::string(e.what()) +
                     "); delete it to start a new one");
  }
  read_entry<CacheDocument>(path_, document, "$");
  return document;
}

void TuningCache::save(const json& document) const {
  // The cache's folder is made if missing (write_file_atomically).
  write_file_atomically(path_, [&](std::ostream& out) { out << document.dump(2) << '\n'; });
}

std::optional<Calibration> TuningCache::calibration() const {
  const json document = load();
  const std::string key = machine_key();
  const auto it = document["calibrations"].find(key);
  if (it == document["calibrations"].end() || !it->is_object() ||
      it->value("cost_model_version", 1) != kCostModelVersion) {
    return std::nullopt;
  }
  return from_cached(read_entry<CachedCalibration>(path_, *it, "$.calibrations." + key));
}

void TuningCache::store_calibration(const Calibration& calibration) {
  json document = load();
  document["calibrations"][machine_key()] = to_json_value(to_cached(calibration));
  save(document);
}

std::optional<Variant> TuningCache::choice(const SceneRecord& scene, double diameter, int threads,
                                           const std::string& setting) const {
  const json document = load();
  const std::string key = choice_key(scene, diameter, threads, setting);
  const auto it = document["choices"].find(key);
  if (it == document["choices"].end()) return std::nullopt;
  return parse_variant(read_entry<CachedChoice>(path_, *it, "$.choices." + key).variant);
}

void TuningCache::store_choice(const SceneRecord& scene, double diameter, int threads,
                               const Variant& variant, double seconds, const std::string& setting) {
  json document = load();
  document["choices"][choice_key(scene, diameter, threads, setting)] =
      to_json_value(CachedChoice{to_string(variant), seconds});
  save(document);
}

std::string TuningCache::calibration_text(const Calibration& calibration) {
  return to_json_value(to_cached(calibration)).dump();
}

Calibration TuningCache::calibration_from_text(const std::string& text) {
  return from_cached(read_entry<CachedCalibration>("calibration", json::parse(text), "$"));
}

}  // namespace contactlab::tuner
