// The tuning cache (tune.hpp): calibrations per machine and build, choices per machine, build,
// scene, diameter and thread count, in one JSON file written atomically.
#include <fmt/core.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "contactlab/kernels/atomic_file.hpp"
#include "contactlab/kernels/error.hpp"
#include "contactlab/tuner/context.hpp"
#include "contactlab/tuner/tune.hpp"

namespace contactlab::tuner {
namespace {

using nlohmann::json;

// Calibrations and choices hold for one machine and one build.
std::string machine_key() {
  const MachineInfo& m = machine_info();
  const BuildRecord b = build_record();
  return fmt::format("{}|{} cpus|{}|{}", m.cpu_model, m.pus, b.flags, b.git_commit);
}

// A calibration stored by a cost model with other constants (another kCostModelVersion) is a
// cache miss.
constexpr int kCostModelVersion = 2;

json costs_json(const MachineCosts& c) {
  json j;
  for (const auto& [name, field] : kMachineCostFields) j[name] = c.*field;
  return j;
}

MachineCosts costs_from_json(const json& j) {
  MachineCosts c;
  for (const auto& [name, field] : kMachineCostFields) c.*field = j.at(name).get<double>();
  return c;
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
  if (!in)
    return json{
        {"schema_version", 1}, {"calibrations", json::object()}, {"choices", json::object()}};
  try {
    json document = json::parse(in);
    if (document.value("schema_version", 0) != 1 || !document.contains("calibrations") ||
        !document.contains("choices")) {
      throw InputError(path_ + ": not a contactlab tuning cache (schema_version 1)");
    }
    return document;
  } catch (const json::exception& e) {
    throw InputError(path_ + ": tuning cache is not valid JSON (" + std::string(e.what()) +
                     "); delete it to start a new one");
  }
}

void TuningCache::save(const json& document) const {
  std::filesystem::create_directories(std::filesystem::path(path_).parent_path());
  write_file_atomically(path_, [&](std::ostream& out) { out << document.dump(2) << '\n'; });
}

std::optional<Calibration> TuningCache::calibration() const {
  const json document = load();
  const auto it = document["calibrations"].find(machine_key());
  if (it == document["calibrations"].end() ||
      it->value("cost_model_version", 1) != kCostModelVersion) {
    return std::nullopt;
  }
  Calibration c;
  c.source = "cache";
  c.seconds = it->at("seconds").get<double>();
  c.threads = it->at("threads").get<int>();
  for (const auto& [key, value] : it->at("structures").items()) {
    c.structures[key] = {costs_from_json(value.at("costs")),
                         value.at("rms_relative_error").get<double>(), value.at("runs").get<int>()};
  }
  return c;
}

void TuningCache::store_calibration(const Calibration& calibration) {
  json document = load();
  json structures = json::object();
  for (const auto& [key, s] : calibration.structures) {
    structures[key] = {{"costs", costs_json(s.costs)},
                       {"rms_relative_error", s.rms_relative_error},
                       {"runs", s.runs}};
  }
  document["calibrations"][machine_key()] = {{"cost_model_version", kCostModelVersion},
                                             {"seconds", calibration.seconds},
                                             {"threads", calibration.threads},
                                             {"structures", structures}};
  save(document);
}

namespace {
std::string choice_key(const SceneRecord& scene, double diameter, int threads) {
  return fmt::format("{}|{}|{}|{:.17g}|{}", machine_key(), scene.checksum, scene.n, diameter,
                     threads);
}
}  // namespace

std::optional<Variant> TuningCache::choice(const SceneRecord& scene, double diameter,
                                           int threads) const {
  const json document = load();
  const auto it = document["choices"].find(choice_key(scene, diameter, threads));
  if (it == document["choices"].end()) return std::nullopt;
  return parse_variant(it->at("variant").get<std::string>());
}

void TuningCache::store_choice(const SceneRecord& scene, double diameter, int threads,
                               const Variant& variant, double seconds) {
  json document = load();
  document["choices"][choice_key(scene, diameter, threads)] = {{"variant", to_string(variant)},
                                                               {"detect_s", seconds}};
  save(document);
}

}  // namespace contactlab::tuner
