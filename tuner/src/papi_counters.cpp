#include "contactlab/tuner/papi_counters.hpp"

#include <fmt/core.h>
#include <pthread.h>

#include <algorithm>
#include <mutex>
#include <optional>

#include "contactlab/kernels/error.hpp"

#if CONTACTLAB_HAVE_PAPI
#include <papi.h>
#endif

namespace contactlab::tuner {

std::string PapiFormula::text() const {
  auto sum = [](const std::vector<std::string>& names) {
    std::string s;
    for (const auto& n : names) s += (s.empty() ? "" : " + ") + n;
    return names.size() > 1 ? "(" + s + ")" : s;
  };
  return "100 * " + sum(numerator) + " / " + sum(denominator);
}

const std::vector<PapiFormula>& papi_l1_formulas() {
  static const std::vector<PapiFormula> formulas{
      {{"PAPI_L1_DCM"}, {"PAPI_LST_INS"}, "load/store instructions"},
      {{"PAPI_L1_DCM"}, {"PAPI_LD_INS", "PAPI_SR_INS"}, "load/store instructions"},
      {{"PAPI_L1_DCM"}, {"PAPI_L1_DCA"}, "accesses"},
      {{"perf::L1-DCACHE-LOAD-MISSES"}, {"perf::L1-DCACHE-LOADS"}, "loads"},
  };
  return formulas;
}

const std::vector<PapiFormula>& papi_l2_formulas() {
  static const std::vector<PapiFormula> formulas{
      {{"PAPI_L2_DCM"}, {"PAPI_LST_INS"}, "load/store instructions"},
      {{"PAPI_L2_DCM"}, {"PAPI_LD_INS", "PAPI_SR_INS"}, "load/store instructions"},
      {{"PAPI_L2_TCM"},
       {"PAPI_LST_INS"},
       "load/store instructions (L2 misses include instruction fetches)"},
      // A local rate (misses per L2 access), not comparable with the per-instruction ones.
      {{"PAPI_L2_DCM"}, {"PAPI_L2_DCA"}, "L2 data accesses (local miss rate)"},
  };
  return formulas;
}

namespace {

[[maybe_unused]] std::vector<std::string> formula_events(const PapiFormula& f) {
  std::vector<std::string> events = f.numerator;
  events.insert(events.end(), f.denominator.begin(), f.denominator.end());
  return events;
}

std::vector<std::string> all_formula_events() {
  std::vector<std::string> names;
  for (const auto* list : {&papi_l1_formulas(), &papi_l2_formulas()}) {
    for (const auto& f : *list) {
      for (const auto& e : formula_events(f)) {
        if (std::find(names.begin(), names.end(), e) == names.end()) names.push_back(e);
      }
    }
  }
  return names;
}

// 100 * sum(numerator) / sum(denominator) from named totals; nullopt when the denominator is 0
// or an event is missing.
std::optional<double> rate(const PapiFormula& f, const std::vector<EventCount>& events) {
  auto total = [&](const std::string& name) -> std::optional<double> {
    for (const auto& e : events) {
      if (e.name == name) return static_cast<double>(e.total);
    }
    return std::nullopt;
  };
  double num = 0.0, den = 0.0;
  for (const auto& n : f.numerator) {
    const auto v = total(n);
    if (!v) return std::nullopt;
    num += *v;
  }
  for (const auto& n : f.denominator) {
    const auto v = total(n);
    if (!v) return std::nullopt;
    den += *v;
  }
  if (den <= 0.0) return std::nullopt;
  return 100.0 * num / den;
}

[[maybe_unused]] bool contains_all(const std::vector<std::string>& set,
                                   const std::vector<std::string>& wanted) {
  return std::all_of(wanted.begin(), wanted.end(), [&](const std::string& w) {
    return std::find(set.begin(), set.end(), w) != set.end();
  });
}

constexpr const char* kRegion = "detection loop, every OpenMP thread (one event set each), summed";

}  // namespace

#if CONTACTLAB_HAVE_PAPI

namespace {

unsigned long papi_thread_id() { return static_cast<unsigned long>(pthread_self()); }

std::string papi_error(int code) {
  const char* s = PAPI_strerror(code);
  return s ? std::string(s) : fmt::format("PAPI error {}", code);
}

// Adds `names` to a fresh event set on the calling thread, starts and stops it. Returns the
// first failure ("NAME: reason" or "PAPI_start: reason"), or nullopt when the set works.
std::optional<std::string> try_event_set(const std::vector<std::string>& names) {
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

struct PapiCounters::Impl {
  struct ThreadSlot {
    int event_set = PAPI_NULL;
    std::vector<long long> values;
    int error = PAPI_OK;
    std::string step;  // the call that failed
  };

  std::vector<std::string> names;
  std::vector<int> codes;
  std::optional<PapiFormula> l1, l2;
  bool available = false;
  std::string reason;
  std::vector<std::string> notes;
  std::vector<ThreadSlot> slots;                   // this region's threads
  std::vector<std::vector<std::uint64_t>> totals;  // [thread][event] over counted regions
  int counted_runs = 0;
  bool in_region = false;
};

PapiCounters::PapiCounters(std::vector<std::string> events) : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  const PapiInfo& info = papi_info();
  if (!info.initialized) {
    m.reason = info.error;
    m.names = std::move(events);
    return;
  }
  if (!events.empty()) {
    for (const auto& name : events) {
      int code = 0;
      const int rc = PAPI_event_name_to_code(name.c_str(), &code);
      if (rc != PAPI_OK && !is_known_preset(name)) {
        throw InputError(fmt::format(
            "unknown PAPI event '{}': not a PAPI preset nor a native event of this machine ({}); "
            "list them with papi_avail and papi_native_avail",
            name, papi_error(rc)));
      }
    }
    m.names = std::move(events);
    if (const auto failure = try_event_set(m.names)) {
      m.reason = "cannot count the requested events here: " + *failure;
      return;
    }
    for (const auto& f : papi_l1_formulas()) {
      if (contains_all(m.names, formula_events(f))) {
        m.l1 = f;
        break;
      }
    }
    for (const auto& f : papi_l2_formulas()) {
      if (contains_all(m.names, formula_events(f))) {
        m.l2 = f;
        break;
      }
    }
  } else {
    // First usable candidate of each level, with the events of both fitting in one set.
    std::vector<std::string> failures;
    for (auto [formulas, chosen] :
         {std::pair{&papi_l1_formulas(), &m.l1}, std::pair{&papi_l2_formulas(), &m.l2}}) {
      for (const auto& f : *formulas) {
        std::vector<std::string> trial = m.names;
        for (const auto& e : formula_events(f)) {
          if (std::find(trial.begin(), trial.end(), e) == trial.end()) trial.push_back(e);
        }
        if (const auto failure = try_event_set(trial)) {
          failures.push_back(f.text() + " (" + *failure + ")");
          continue;
        }
        m.names = std::move(trial);
        *chosen = f;
        break;
      }
    }
    if (!m.l1 && !m.l2) {
      std::string list;
      for (const auto& f : failures) list += (list.empty() ? "" : "; ") + f;
      m.reason = "no L1 or L2 data-cache miss formula can be counted here: " + list;
      return;
    }
    if (!m.l1) m.notes.push_back("no L1 formula can be counted here");
    if (!m.l2) m.notes.push_back("no L2 formula can be counted here");
  }
  for (const auto& name : m.names) {
    int code = 0;
    PAPI_event_name_to_code(name.c_str(), &code);
    m.codes.push_back(code);
  }
  m.available = true;
}

PapiCounters::~PapiCounters() = default;

bool PapiCounters::available() const { return impl_->available; }
const std::vector<std::string>& PapiCounters::event_names() const { return impl_->names; }

void PapiCounters::region_begin(int threads) {
  Impl& m = *impl_;
  m.in_region = m.available;
  if (!m.available) return;
  m.slots.assign(threads, {});
  for (auto& slot : m.slots) slot.values.assign(m.codes.size(), 0);
  if (m.totals.size() < static_cast<std::size_t>(threads)) {
    m.totals.resize(threads, std::vector<std::uint64_t>(m.codes.size(), 0));
  }
}

// Runs on each OpenMP thread: nothing here may throw, so failures are kept for region_end.
void PapiCounters::thread_begin(int thread) {
  Impl& m = *impl_;
  if (!m.in_region) return;
  Impl::ThreadSlot& slot = m.slots[thread];
  auto check = [&](int rc, const char* step) {
    if (rc != PAPI_OK && slot.error == PAPI_OK) {
      slot.error = rc;
      slot.step = step;
    }
    return rc == PAPI_OK;
  };
  if (!check(PAPI_register_thread(), "PAPI_register_thread")) return;
  if (!check(PAPI_create_eventset(&slot.event_set), "PAPI_create_eventset")) return;
  if (!check(PAPI_add_events(slot.event_set, m.codes.data(), static_cast<int>(m.codes.size())),
             "PAPI_add_events")) {
    return;
  }
  check(PAPI_start(slot.event_set), "PAPI_start");
}

void PapiCounters::thread_end(int thread) {
  Impl& m = *impl_;
  if (!m.in_region) return;
  Impl::ThreadSlot& slot = m.slots[thread];
  if (slot.event_set == PAPI_NULL) return;
  if (slot.error == PAPI_OK) {
    const int rc = PAPI_stop(slot.event_set, slot.values.data());
    if (rc != PAPI_OK) {
      slot.error = rc;
      slot.step = "PAPI_stop";
    }
  }
  PAPI_cleanup_eventset(slot.event_set);
  PAPI_destroy_eventset(&slot.event_set);
}

void PapiCounters::region_end() {
  Impl& m = *impl_;
  if (!m.in_region) return;
  m.in_region = false;
  for (std::size_t t = 0; t < m.slots.size(); ++t) {
    const auto& slot = m.slots[t];
    if (slot.error != PAPI_OK) {
      m.available = false;
      m.reason = fmt::format("thread {}: {}: {}", t, slot.step, papi_error(slot.error));
      return;
    }
  }
  for (std::size_t t = 0; t < m.slots.size(); ++t) {
    for (std::size_t e = 0; e < m.codes.size(); ++e) {
      m.totals[t][e] += static_cast<std::uint64_t>(std::max(0LL, m.slots[t].values[e]));
    }
  }
  ++m.counted_runs;
}

#else  // built without PAPI

const PapiInfo& papi_info() {
  static const PapiInfo info = [] {
    PapiInfo i;
    i.error = "built without PAPI";
    for (const auto& name : all_formula_events())
      i.cache_events.push_back({name, false, "built without PAPI"});
    return i;
  }();
  return info;
}

struct PapiCounters::Impl {
  std::vector<std::string> names;
  std::optional<PapiFormula> l1, l2;
  bool available = false;
  std::string reason = "built without PAPI";
  std::vector<std::string> notes;
  std::vector<std::vector<std::uint64_t>> totals;
  int counted_runs = 0;
};

PapiCounters::PapiCounters(std::vector<std::string> events) : impl_(std::make_unique<Impl>()) {
  impl_->names = std::move(events);
}
PapiCounters::~PapiCounters() = default;
bool PapiCounters::available() const { return false; }
const std::vector<std::string>& PapiCounters::event_names() const { return impl_->names; }
void PapiCounters::region_begin(int) {}
void PapiCounters::thread_begin(int) {}
void PapiCounters::thread_end(int) {}
void PapiCounters::region_end() {}

#endif

CounterRecord PapiCounters::record() const {
  const Impl& m = *impl_;
  CounterRecord r;
  r.source = "papi";
  r.region = kRegion;
  r.notes = m.notes;
  if (!m.available || m.counted_runs == 0) {
    r.available = false;
    r.reason = !m.reason.empty() ? m.reason : "no run was counted";
    return r;
  }
  r.available = true;
  r.counted_runs = m.counted_runs;
  for (std::size_t e = 0; e < m.names.size(); ++e) {
    EventCount count{m.names[e], 0, {}};
    for (const auto& thread : m.totals) {
      count.per_thread.push_back(thread[e]);
      count.total += thread[e];
    }
    r.events.push_back(std::move(count));
  }
  if (m.l1) {
    r.l1_miss_percent = rate(*m.l1, r.events);
    r.l1_formula = m.l1->text() + " (per " + m.l1->basis + ")";
  }
  if (m.l2) {
    r.l2_miss_percent = rate(*m.l2, r.events);
    r.l2_formula = m.l2->text() + " (per " + m.l2->basis + ")";
  }
  return r;
}

}  // namespace contactlab::tuner
