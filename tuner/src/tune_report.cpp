// The tune report's field tables: one list of names per record for writing and strict reading.
#include "contactlab/tuner/tune_report.hpp"

#include <cerrno>
#include <cstring>
#include <fstream>

#include "contactlab/kernels/error.hpp"
#include "contactlab/tuner/field_table.hpp"
#include "context_tables.hpp"

namespace contactlab::tuner {

template <>
struct FieldTable<VerifiedTiming> {
  using T = VerifiedTiming;
  static constexpr auto kFields =
      std::tuple{field("median_s", &T::median_s), field("ci95_low_s", &T::ci95_low_s),
                 field("ci95_high_s", &T::ci95_high_s), field("samples_s", &T::samples_s)};
};

template <>
struct FieldTable<RatioToExhaustive> {
  using T = RatioToExhaustive;
  static constexpr auto kFields =
      std::tuple{field("ratio_minus_one", &T::ratio_minus_one), field("ci95", &T::ci95)};
};

// The verification's fields of an entry, shared by methods and classic formulas.
template <class T>
constexpr auto verified_fields() {
  return std::tuple{field("measured", &T::measured).only_when_set(),
                    field("regret", &T::regret).only_when_set(),
                    field("regret_ci95", &T::regret_ci95).only_when_set(),
                    field("vs_exhaustive", &T::vs_exhaustive).only_when_set()};
}

template <>
struct FieldTable<Verified> {
  using T = Verified;
  static constexpr auto kFields = verified_fields<Verified>();
};

template <>
struct FieldTable<MethodEntry> {
  using T = MethodEntry;
  static constexpr auto kFields = std::tuple_cat(
      std::tuple{field("method", &T::method), field("variant", &T::variant),
                 field("chunk", &T::chunk), field("timed_runs", &T::timed_runs),
                 field("tuning_cost_s", &T::tuning_cost_s),
                 field("predicted_s", &T::predicted_s).only_when_set(),
                 field("structures", &T::structures).only_when_set(),
                 field("chunk_search_timed_runs", &T::chunk_search_timed_runs).only_when_set(),
                 field("evaluations", &T::evaluations).only_when_set(),
                 field("screening_cost_s", &T::screening_cost_s).only_when_set(),
                 field("model_cost_s", &T::model_cost_s).only_when_set(),
                 field("chunk_search_cost_s", &T::chunk_search_cost_s).only_when_set(),
                 field("screening", &T::screening).only_when_set(),
                 field("chunks_measured", &T::chunks_measured).only_when_set(),
                 field("largest_equivalent_chunk", &T::largest_equivalent_chunk).only_when_set(),
                 field("rounds", &T::rounds).only_when_set()},
      verified_fields<Verified>());
};

template <>
struct FieldTable<ClassicEntry> {
  using T = ClassicEntry;
  static constexpr auto kFields = std::tuple_cat(
      std::tuple{field("name", &T::name), field("chunk", &T::chunk), field("inputs", &T::inputs),
                 field("structure", &T::structure), field("variant", &T::variant).only_when_set()},
      verified_fields<Verified>());
};

template <>
struct FieldTable<Prediction> {
  using T = Prediction;
  static constexpr auto kFields =
      std::tuple{field("threads", &T::threads), field("variant", &T::variant),
                 field("predicted_s", &T::predicted_s), field("label", &T::label)};
};

template <>
struct FieldTable<VerificationSummary> {
  using T = VerificationSummary;
  static constexpr auto kFields =
      std::tuple{field("rounds", &T::rounds), field("distinct_variants", &T::distinct_variants),
                 field("best", &T::best), field("regret_against", &T::regret_against)};
};

template <>
struct FieldTable<CalibrationSummary> {
  using T = CalibrationSummary;
  static constexpr auto kFields =
      std::tuple{field("source", &T::source), field("seconds", &T::seconds)};
};

namespace {
void check_tune_version(const JsonIn& at, const int& version) {
  if (version != kTuneSchemaVersion) {
    at.fail("schema_version " + std::to_string(version) + " is not the supported version " +
            std::to_string(kTuneSchemaVersion));
  }
}
}  // namespace

template <>
struct FieldTable<TuneMpi> {
  using T = TuneMpi;
  static constexpr auto kFields =
      std::tuple{field("mode", &T::mode), field("ranks", &T::ranks), field("block", &T::block),
                 field("halo_width", &T::halo_width)};
};

template <>
struct FieldTable<TuneDocument> {
  using T = TuneDocument;
  static constexpr auto kFields =
      std::tuple{field("schema_version", &T::schema_version).checked(&check_tune_version),
                 field("context", &T::context),
                 field("scene", &T::scene),
                 field("diameter", &T::diameter),
                 field("threads", &T::threads),
                 field("chunk_grid", &T::chunk_grid),
                 field("calibration", &T::calibration),
                 field("methods", &T::methods),
                 field("classic", &T::classic),
                 field("predictions", &T::predictions),
                 field("verification", &T::verification).only_when_set(),
                 field("mpi", &T::mpi).only_when_set()};
  static void validate(const JsonIn& in, const T& v) {
    if (v.methods.empty()) in.fail("no tuning method ran");
    for (const Prediction& p : v.predictions) {
      if (p.label.find("predicted") == std::string::npos)
        in.fail("a prediction's label must say it is predicted: '" + p.label + "'");
    }
  }
};

const MethodEntry* TuneDocument::method(const std::string& name) const {
  for (const MethodEntry& m : methods) {
    if (m.method == name) return &m;
  }
  return nullptr;
}

nlohmann::json to_json_value(const Verified& verified) { return to_json_value<Verified>(verified); }

nlohmann::json to_json_value(const TuneDocument& document) {
  return to_json_value<TuneDocument>(document);
}

void read(const JsonIn& in, TuneDocument& out) { read_record(in, out); }

TuneDocument read_tune_document(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot open: " + std::strerror(errno));
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(in);
  } catch (const nlohmann::json::parse_error& e) {
    throw InputError(path + ": not valid JSON: " + e.what());
  }
  TuneDocument document;
  try {
    read(JsonIn(j, "$"), document);
  } catch (const InputError& e) {
    throw InputError(path + ": " + e.what());
  }
  return document;
}

}  // namespace contactlab::tuner
