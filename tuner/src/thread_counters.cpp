#include "contactlab/tuner/thread_counters.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <tuple>

#include "contactlab/kernels/error.hpp"

namespace contactlab::tuner {

std::string PapiFormula::text() const {
  auto sum = [](const std::vector<std::string>& names) {
    std::string s;
    for (const auto& n : names) s += (s.empty() ? "" : " + ") + n;
    return names.size() > 1 ? "(" + s + ")" : s;
  };
  return "100 * " + sum(numerator) + " / " + sum(denominator);
}

std::vector<std::string> PapiFormula::events() const {
  std::vector<std::string> all = numerator;
  all.insert(all.end(), denominator.begin(), denominator.end());
  return all;
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

constexpr const char* kRegion = "detection loop, every OpenMP thread (one event set each), summed";

bool contains_all(const std::vector<std::string>& set, const std::vector<std::string>& wanted) {
  return std::all_of(wanted.begin(), wanted.end(), [&](const std::string& w) {
    return std::find(set.begin(), set.end(), w) != set.end();
  });
}

std::string join(const std::vector<std::string>& items) {
  std::string s;
  for (const auto& i : items) s += (s.empty() ? "" : "; ") + i;
  return s;
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

}  // namespace

ThreadCounters::ThreadCounters(std::unique_ptr<CounterBackend> backend,
                               std::vector<std::string> events,
                               std::vector<PapiFormula> l1_formulas,
                               std::vector<PapiFormula> l2_formulas)
    : backend_(std::move(backend)) {
  if (std::string why = backend_->unavailable_reason(); !why.empty()) {
    reason_ = std::move(why);
    names_ = std::move(events);
    return;
  }
  if (!events.empty()) {
    for (const auto& name : events) {
      if (const auto why = backend_->unknown_event(name)) throw InputError(*why);
    }
    names_ = std::move(events);
    if (const auto failure = backend_->try_events(names_)) {
      reason_ = "cannot count the requested events here: " + *failure;
      return;
    }
    for (auto [formulas, chosen] : {std::pair{&l1_formulas, &l1_}, std::pair{&l2_formulas, &l2_}}) {
      for (const auto& f : *formulas) {
        if (contains_all(names_, f.events())) {
          *chosen = f;
          break;
        }
      }
    }
  } else {
    // First usable candidate of each level, with the events of both fitting in one set.
    std::vector<std::string> failures;
    for (auto [formulas, chosen] : {std::pair{&l1_formulas, &l1_}, std::pair{&l2_formulas, &l2_}}) {
      for (const auto& f : *formulas) {
        std::vector<std::string> trial = names_;
        for (const auto& e : f.events()) {
          if (std::find(trial.begin(), trial.end(), e) == trial.end()) trial.push_back(e);
        }
        if (const auto failure = backend_->try_events(trial)) {
          failures.push_back(f.text() + " (" + *failure + ")");
          continue;
        }
        names_ = std::move(trial);
        *chosen = f;
        break;
      }
    }
    if (!l1_ && !l2_) {
      reason_ = "no L1 or L2 data-cache miss formula can be counted here: " + join(failures);
      return;
    }
    if (!l1_) notes_.push_back("no L1 formula can be counted here");
    if (!l2_) notes_.push_back("no L2 formula can be counted here");
  }
  available_ = true;
}

ThreadCounters::~ThreadCounters() = default;

void ThreadCounters::region_begin(int threads) {
  in_region_ = available_ && threads > 0;
  if (!in_region_) return;
  backend_->prepare(names_, threads);
  slots_.assign(threads, Slot{});
  for (auto& slot : slots_) slot.values.assign(names_.size(), 0);
  if (totals_.size() < static_cast<std::size_t>(threads)) {
    totals_.resize(threads, std::vector<std::uint64_t>(names_.size(), 0));
  }
}

// Runs on each OpenMP thread: nothing here may throw, so failures are kept for region_end.
void ThreadCounters::thread_begin(int thread) {
  if (!in_region_ || thread < 0 || static_cast<std::size_t>(thread) >= slots_.size()) return;
  Slot& slot = slots_[thread];
  slot.began = true;
  slot.status = backend_->start(thread);
}

void ThreadCounters::thread_end(int thread) {
  if (!in_region_ || thread < 0 || static_cast<std::size_t>(thread) >= slots_.size()) return;
  Slot& slot = slots_[thread];
  if (!slot.began || !slot.status.ok()) return;
  slot.status = backend_->stop(thread, slot.values);
  slot.ended = true;
}

void ThreadCounters::region_end() {
  if (!in_region_) return;
  in_region_ = false;
  std::vector<std::string> failures;
  for (std::size_t t = 0; t < slots_.size(); ++t) {
    const Slot& slot = slots_[t];
    if (!slot.status.ok()) {
      failures.push_back(fmt::format("thread {}: {}: {}", t, slot.status.step,
                                     backend_->describe(slot.status.code)));
    } else if (!slot.began) {
      failures.push_back(fmt::format("thread {}: not run in the region (fewer threads than {})", t,
                                     slots_.size()));
    } else if (!slot.ended) {
      failures.push_back(fmt::format("thread {}: started but never stopped", t));
    }
  }
  if (!failures.empty()) {
    available_ = false;
    reason_ = join(failures);
    return;
  }
  for (std::size_t t = 0; t < slots_.size(); ++t) {
    for (std::size_t e = 0; e < names_.size(); ++e) {
      totals_[t][e] += static_cast<std::uint64_t>(std::max(0LL, slots_[t].values[e]));
    }
  }
  ++counted_runs_;
}

CounterRecord ThreadCounters::record() const {
  CounterRecord r;
  r.source = backend_->name();
  r.region = kRegion;
  r.notes = notes_;
  if (!available_ || counted_runs_ == 0) {
    r.available = false;
    r.reason = !reason_.empty() ? reason_ : "no run was counted";
    return r;
  }
  r.available = true;
  r.counted_runs = counted_runs_;
  for (std::size_t e = 0; e < names_.size(); ++e) {
    EventCount count{names_[e], 0, {}};
    for (const auto& thread : totals_) {
      count.per_thread.push_back(thread[e]);
      count.total += thread[e];
    }
    r.events.push_back(std::move(count));
  }
  for (auto [level, formula, percent, text] :
       {std::tuple{"L1", &l1_, &r.l1_miss_percent, &r.l1_formula},
        std::tuple{"L2", &l2_, &r.l2_miss_percent, &r.l2_formula}}) {
    if (!*formula) continue;
    *percent = rate(**formula, r.events);
    if (*percent) {
      *text = (*formula)->text() + " (per " + (*formula)->basis + ")";
    } else {
      r.notes.push_back(
          fmt::format("no {} rate: the denominator of {} counted 0", level, (*formula)->text()));
    }
  }
  return r;
}

}  // namespace contactlab::tuner
