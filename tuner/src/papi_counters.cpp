#include "contactlab/tuner/papi_counters.hpp"

#include <fmt/core.h>
#include <pthread.h>

#include <algorithm>
#include <optional>

#if CONTACTLAB_HAVE_PAPI
#include <papi.h>
#endif

namespace contactlab::tuner {

namespace {

std::vector<std::string> all_formula_events() {
  std::vector<std::string> names;
  for (const auto* list : {&papi_l1_formulas(), &papi_l2_formulas()}) {
    for (const auto& f : *list) {
      for (const auto& e : f.events()) {
        if (std::find(names.begin(), names.end(), e) == names.end()) names.push_back(e);
      }
    }
  }
  return names;
}

[[maybe_unused]] std::string join(const std::vector<std::string>& items, const char* separator) {
  std::string s;
  for (const auto& i : items) s += (s.empty() ? "" : separator) + i;
  return s;
}

}  // namespace

#if CONTACTLAB_HAVE_PAPI

namespace {

unsigned long papi_thread_id() { return static_cast<unsigned long>(pthread_self()); }

std::string papi_error(int code) {
  const char* s = PAPI_strerror(code);
  return s ? std::string(s) : fmt::format("PAPI error {}", code);
}

// Why the component that would count `name` is disabled ("PAPI component perf_event is
// disabled: Error libpfm4 no default PMU found"), or nullopt when it is enabled or unknown. A
// disabled component lists no native events, so "perf::TASK-CLOCK" does not resolve there and
// would look like a typo: its prefix ("perf", the component's short name) finds the component.
// Presets resolve even then, and PAPI names their component.
std::optional<std::string> disabled_component(const std::string& name) {
  int component = -1;
  if (const auto separator = name.find("::"); separator != std::string::npos) {
    const std::string prefix = name.substr(0, separator);
    for (int c = 0; c < PAPI_num_components() && component < 0; ++c) {
      const PAPI_component_info_t* info = PAPI_get_component_info(c);
      if (info && (prefix == info->short_name || prefix == info->name)) component = c;
    }
  }
  if (component < 0) {
    int code = 0;
    if (PAPI_event_name_to_code(name.c_str(), &code) == PAPI_OK) {
      component = PAPI_get_event_component(code);
    }
  }
  if (component < 0) return std::nullopt;
  const PAPI_component_info_t* info = PAPI_get_component_info(component);
  // PAPI_EDELAY_INIT: initialised on first use of its events, not disabled.
  if (!info || info->disabled == PAPI_OK || info->disabled == PAPI_EDELAY_INIT) return std::nullopt;
  return fmt::format("PAPI component {} is disabled: {}", info->name, info->disabled_reason);
}

// Adds `names` to a fresh event set on the calling thread, starts and stops it. Returns the
// first failure ("NAME: reason" or "PAPI_start: reason"), or nullopt when the set works.
std::optional<std::string> try_event_set(const std::vector<std::string>& names) {
  for (const auto& name : names) {
    if (const auto why = disabled_component(name)) return name + ": " + *why;
  }
  int set = PAPI_NULL;
  int rc = PAPI_create_eventset(&set);
  if (rc != PAPI_OK) return "PAPI_create_eventset: " + papi_error(rc);
  std::optional<std::string> failure;
  for (const auto& name : names) {
    rc = PAPI_add_named_event(set, name.c_str());
    if (rc != PAPI_OK) {
      failure = name + ": " + papi_error(rc);
      break;
    }
  }
  if (!failure && !names.empty()) {
    rc = PAPI_start(set);
    if (rc != PAPI_OK) {
      failure = "PAPI_start: " + papi_error(rc);
    } else {
      std::vector<long long> values(names.size());
      rc = PAPI_stop(set, values.data());
      if (rc != PAPI_OK) failure = "PAPI_stop: " + papi_error(rc);
    }
  }
  PAPI_cleanup_eventset(set);
  PAPI_destroy_eventset(&set);
  return failure;
}

bool is_known_preset(const std::string& name) {
  int code = 0 | PAPI_PRESET_MASK;
  if (PAPI_enum_event(&code, PAPI_ENUM_FIRST) != PAPI_OK) return false;
  do {
    char text[PAPI_MAX_STR_LEN] = {};
    if (PAPI_event_code_to_name(code, text) == PAPI_OK && name == text) return true;
  } while (PAPI_enum_event(&code, PAPI_ENUM_ALL) == PAPI_OK);
  return false;
}

class PapiBackend final : public CounterBackend {
 public:
  std::string name() const override { return "papi"; }

  std::string unavailable_reason() const override {
    const PapiInfo& info = papi_info();
    return info.initialized ? "" : info.error;
  }

  std::optional<std::string> unknown_event(const std::string& event) const override {
    int code = 0;
    const int rc = PAPI_event_name_to_code(event.c_str(), &code);
    if (rc == PAPI_OK || is_known_preset(event) || disabled_component(event)) return std::nullopt;
    return fmt::format(
        "unknown PAPI event '{}': not a PAPI preset nor a native event of this machine ({}); "
        "list them with papi_avail and papi_native_avail",
        event, papi_error(rc));
  }

  std::optional<std::string> try_events(const std::vector<std::string>& events) override {
    return try_event_set(events);
  }

  void prepare(const std::vector<std::string>& events, int threads) override {
    codes_.clear();
    for (const auto& name : events) {
      int code = 0;
      PAPI_event_name_to_code(name.c_str(), &code);  // try_events accepted every name
      codes_.push_back(code);
    }
    sets_.assign(threads, PAPI_NULL);
  }

  CounterStatus start(int thread) noexcept override {
    int& set = sets_[thread];
    int rc = PAPI_register_thread();
    if (rc != PAPI_OK) return {"PAPI_register_thread", rc};
    rc = PAPI_create_eventset(&set);
    if (rc != PAPI_OK) return {"PAPI_create_eventset", rc};
    rc = PAPI_add_events(set, codes_.data(), static_cast<int>(codes_.size()));
    if (rc != PAPI_OK) {
      release(set);
      return {"PAPI_add_events", rc};
    }
    rc = PAPI_start(set);
    if (rc != PAPI_OK) {
      release(set);
      return {"PAPI_start", rc};
    }
    return {};
  }

  CounterStatus stop(int thread, std::span<long long> values) noexcept override {
    int& set = sets_[thread];
    const int rc = PAPI_stop(set, values.data());
    release(set);
    if (rc != PAPI_OK) return {"PAPI_stop", rc};
    return {};
  }

  std::string describe(int code) const override { return papi_error(code); }

 private:
  static void release(int& set) noexcept {
    PAPI_cleanup_eventset(set);
    PAPI_destroy_eventset(&set);
  }

  std::vector<int> codes_;
  std::vector<int> sets_;  // per thread; each thread touches only its own
};

}  // namespace

const PapiInfo& papi_info() {
  static const PapiInfo info = [] {
    PapiInfo i;
    i.built_with_papi = true;
    const int version = PAPI_library_init(PAPI_VER_CURRENT);
    if (version != PAPI_VER_CURRENT) {
      i.error = version > 0
                    ? fmt::format("PAPI_library_init: version mismatch (library {:x}, header {:x})",
                                  version, PAPI_VER_CURRENT)
                    : "PAPI_library_init: " + papi_error(version);
      return i;
    }
    const int rc = PAPI_thread_init(papi_thread_id);
    if (rc != PAPI_OK) {
      i.error = "PAPI_thread_init: " + papi_error(rc);
      return i;
    }
    i.initialized = true;
    const int lib = PAPI_get_opt(PAPI_LIB_VERSION, nullptr);
    i.version = fmt::format("{}.{}.{}.{}", PAPI_VERSION_MAJOR(lib), PAPI_VERSION_MINOR(lib),
                            PAPI_VERSION_REVISION(lib), PAPI_VERSION_INCREMENT(lib));
    i.hardware_counters = PAPI_num_cmp_hwctrs(0);
    for (int c = 0; c < PAPI_num_components(); ++c) {
      const PAPI_component_info_t* component = PAPI_get_component_info(c);
      if (component && !component->disabled) i.components.emplace_back(component->name);
    }
    int code = 0 | PAPI_PRESET_MASK;
    if (PAPI_enum_event(&code, PAPI_ENUM_FIRST) == PAPI_OK) {
      do {
        char text[PAPI_MAX_STR_LEN] = {};
        if (PAPI_event_code_to_name(code, text) == PAPI_OK) i.presets_listed.emplace_back(text);
      } while (PAPI_enum_event(&code, PAPI_PRESET_ENUM_AVAIL) == PAPI_OK);
    }
    for (const auto& name : all_formula_events()) {
      const auto failure = try_event_set({name});
      i.cache_events.push_back({name, !failure, failure.value_or("")});
    }
    return i;
  }();
  return info;
}

PapiProbe papi_probe(const std::vector<std::string>& events) {
  const PapiInfo& info = papi_info();
  if (!info.initialized) return {false, "PAPI cannot be initialised here: " + info.error};
  if (const auto failure = try_event_set(events)) {
    return {false, fmt::format("PAPI cannot count {} here: {}", join(events, ", "), *failure)};
  }
  return {true, ""};
}

std::string papi_disabled_component(const std::string& event) {
  if (!papi_info().initialized) return "";
  return disabled_component(event).value_or("");
}

std::unique_ptr<CounterBackend> make_papi_backend() { return std::make_unique<PapiBackend>(); }

#else  // built without PAPI

namespace {

constexpr const char* kNoPapi = "built without PAPI";

class NoPapiBackend final : public CounterBackend {
 public:
  std::string name() const override { return "papi"; }
  std::string unavailable_reason() const override { return kNoPapi; }
  std::optional<std::string> unknown_event(const std::string&) const override {
    return std::nullopt;
  }
  std::optional<std::string> try_events(const std::vector<std::string>&) override {
    return kNoPapi;
  }
  void prepare(const std::vector<std::string>&, int) override {}
  CounterStatus start(int) noexcept override { return {"start", 0}; }
  CounterStatus stop(int, std::span<long long>) noexcept override { return {"stop", 0}; }
  std::string describe(int) const override { return kNoPapi; }
};

}  // namespace

const PapiInfo& papi_info() {
  static const PapiInfo info = [] {
    PapiInfo i;
    i.error = kNoPapi;
    for (const auto& name : all_formula_events()) i.cache_events.push_back({name, false, kNoPapi});
    return i;
  }();
  return info;
}

PapiProbe papi_probe(const std::vector<std::string>&) { return {false, kNoPapi}; }

std::string papi_disabled_component(const std::string&) { return ""; }

std::unique_ptr<CounterBackend> make_papi_backend() { return std::make_unique<NoPapiBackend>(); }

#endif

PapiCounters::PapiCounters(std::vector<std::string> events)
    : ThreadCounters(make_papi_backend(), std::move(events)) {}

}  // namespace contactlab::tuner
