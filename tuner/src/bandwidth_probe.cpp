#include "contactlab/tuner/bandwidth_probe.hpp"

#include <fmt/core.h>
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <memory>
#include <optional>
#include <stdexcept>

#include "contactlab/kernels/error.hpp"
#include "contactlab/support/json_reader.hpp"
#include "contactlab/tuner/result_schema.hpp"

namespace contactlab::tuner {

namespace {

constexpr std::uint64_t kTriadBytesPerElement = 3 * sizeof(double);  // STREAM's count

// Arrays that are not value-initialised (std::vector would touch every page from one thread,
// putting them all in that thread's memory on a NUMA machine).
struct RawArray {
  explicit RawArray(std::size_t n) : data(new double[n]) {}
  std::unique_ptr<double[]> data;
};

double best_triad_bytes_per_s(double* a, const double* b, const double* c, std::size_t n,
                              int threads, int repetitions) {
  const double scalar = 3.0;
  auto pass = [&] {
    const auto start = std::chrono::steady_clock::now();
#pragma omp parallel for schedule(static) num_threads(threads)
    for (std::size_t i = 0; i < n; ++i) a[i] = b[i] + scalar * c[i];
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  pass();  // untimed: brings the arrays to this thread count's caches
  double best = 0.0;
  for (int r = 0; r < repetitions; ++r) {
    const double seconds = pass();
    if (seconds > 0.0)
      best = std::max(best, static_cast<double>(n * kTriadBytesPerElement) / seconds);
  }
  return best;
}

// Independent chains of x = x * m + a (a multiply and an add each: built without contraction)
// over lanes the compiler vectorises: the core's floating-point throughput, no memory touched.
// kChains x kLanes values stay in registers; the result is returned so nothing is dropped.
double arithmetic_chains(std::uint64_t steps) {
  constexpr int kChains = 8, kLanes = 8;
  double x[kChains][kLanes];
  for (int c = 0; c < kChains; ++c) {
    for (int l = 0; l < kLanes; ++l) x[c][l] = 1.0 + 1e-3 * (c * kLanes + l);
  }
  const double m = 0.999999, a = 1e-7;
  for (std::uint64_t s = 0; s < steps; ++s) {
    for (int c = 0; c < kChains; ++c) {
#pragma omp simd
      for (int l = 0; l < kLanes; ++l) x[c][l] = x[c][l] * m + a;
    }
  }
  double sum = 0.0;
  for (int c = 0; c < kChains; ++c) {
    for (int l = 0; l < kLanes; ++l) sum += x[c][l];
  }
  return sum;
}

}  // namespace

double probe_arithmetic(int threads, int repetitions) {
  if (threads < 1) throw InputError("probe: a thread count below 1");
  if (repetitions < 1) throw InputError("probe: --repetitions must be >= 1");
  constexpr std::uint64_t kSteps = 4'000'000;           // about 20 ms a thread at 3 GHz
  constexpr double kOperations = 2.0 * 8 * 8 * kSteps;  // per thread per run
  double sink = 0.0;
  auto run = [&] {
    double sum = 0.0;
    const auto start = std::chrono::steady_clock::now();
#pragma omp parallel num_threads(threads) reduction(+ : sum)
    sum += arithmetic_chains(kSteps);
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    sink += sum;
    return seconds;
  };
  run();  // untimed: the threads woken, the clock raised
  double best = 0.0;
  for (int r = 0; r < repetitions; ++r) {
    const double seconds = run();
    if (seconds > 0.0) best = std::max(best, kOperations * threads / seconds);
  }
  if (!(sink > 0.0)) throw std::logic_error("probe: the arithmetic gave no result");
  return best;
}

void validate(const ProbeOptions& options) {
  if (options.threads.empty()) throw InputError("probe: no thread count");
  for (std::size_t i = 0; i < options.threads.size(); ++i) {
    if (options.threads[i] < 1) throw InputError("probe: --threads: every count must be >= 1");
    if (i > 0 && options.threads[i] <= options.threads[i - 1]) {
      throw InputError("probe: --threads: counts must be ascending and distinct");
    }
  }
  if (options.working_sets.empty()) throw InputError("probe: no working-set size");
  for (std::size_t i = 0; i < options.working_sets.size(); ++i) {
    if (options.working_sets[i] < std::uint64_t{3} * 1024) {
      throw InputError("probe: --sizes: every working set must be at least 3 KiB");
    }
    if (i > 0 && options.working_sets[i] <= options.working_sets[i - 1]) {
      throw InputError("probe: --sizes: sizes must be ascending and distinct");
    }
  }
  if (options.repetitions < 1) throw InputError("probe: --repetitions must be >= 1");
}

MachineProbe probe_bandwidth(const ProbeOptions& options) {
  validate(options);
  const int most = options.threads.back();
  MachineProbe probe;
  for (const std::uint64_t bytes : options.working_sets) {
    const auto n = static_cast<std::size_t>(bytes / kTriadBytesPerElement);
    RawArray a(n), b(n), c(n);
    double* pa = a.data.get();
    double* pb = b.data.get();
    double* pc = c.data.get();
#pragma omp parallel for schedule(static) num_threads(most)
    for (std::size_t i = 0; i < n; ++i) {
      pa[i] = 0.0;
      pb[i] = 1.0;
      pc[i] = 2.0;
    }
    ProbedWorkingSet set;
    set.bytes = n * kTriadBytesPerElement;
    for (const int t : options.threads) {
      set.bytes_per_s.emplace_back(t,
                                   best_triad_bytes_per_s(pa, pb, pc, n, t, options.repetitions));
    }
    probe.working_sets.push_back(std::move(set));
  }
  for (const int t : options.threads) {
    probe.operations_per_s.emplace_back(t, probe_arithmetic(t, options.repetitions));
  }
  return probe;
}

nlohmann::json probe_document(const MachineProbe& probe, const ProbeOptions& options,
                              const Context& context) {
  nlohmann::json doc;
  doc["schema_version"] = 1;
  doc["kind"] = "contactlab-machine-probe";
  doc["label"] = "measured";
  doc["context"] = context;
  doc["method"] = fmt::format(
      "STREAM's triad a[i] = b[i] + 3 c[i] over three arrays of doubles, OpenMP static schedule, "
      "the arrays first touched by {} threads with that schedule; per working set (the three "
      "arrays together) and thread count one untimed pass, then the best of {} timed passes; "
      "bytes counted as STREAM counts them (24 per element: two reads and a write, not the "
      "write-allocate). Arithmetic: every thread the same 64 independent chains x = x m + a in "
      "registers (no memory), one untimed run, then the best of {} timed ones; operations (a "
      "multiply or an add) a second over all threads.",
      options.threads.back(), options.repetitions, options.repetitions);
  nlohmann::json sets = nlohmann::json::array();
  for (const ProbedWorkingSet& s : probe.working_sets) {
    nlohmann::json points = nlohmann::json::array();
    for (const auto& [threads, bytes_per_s] : s.bytes_per_s) {
      points.push_back({{"threads", threads}, {"bytes_per_s", bytes_per_s}});
    }
    sets.push_back({{"bytes", s.bytes}, {"points", points}});
  }
  doc["working_sets"] = sets;
  nlohmann::json arithmetic = nlohmann::json::array();
  for (const auto& [threads, rate] : probe.operations_per_s) {
    arithmetic.push_back({{"threads", threads}, {"operations_per_s", rate}});
  }
  doc["arithmetic"] = arithmetic;
  return doc;
}

MachineProbe read_machine_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError("machine file " + path + ": cannot be read");
  nlohmann::json doc;
  try {
    doc = nlohmann::json::parse(in);
  } catch (const nlohmann::json::parse_error& e) {
    throw InputError("machine file " + path + ": not JSON (" + e.what() + ")");
  }
  try {
    const JsonIn root(doc, "$");
    ObjectIn top(root);
    int version = 0;
    std::string kind, label, method;
    top("schema_version", version);
    top("kind", kind);
    if (kind != "contactlab-machine-probe") {
      top.field("kind").fail("expected \"contactlab-machine-probe\", got \"" + kind + "\"");
    }
    if (version != 1) top.field("schema_version").fail("this program reads version 1");
    top("label", label);
    top("method", method);
    nlohmann::json context;
    top("context", context);
    MachineProbe probe;
    const JsonIn sets = top.field("working_sets");
    if (!sets.value().is_array() || sets.value().empty()) sets.fail("expected a non-empty array");
    for (std::size_t i = 0; i < sets.value().size(); ++i) {
      ObjectIn set(JsonIn(sets.value()[i], sets.path() + "[" + std::to_string(i) + "]"));
      ProbedWorkingSet s;
      set("bytes", s.bytes);
      const JsonIn points = set.field("points");
      if (!points.value().is_array() || points.value().empty()) {
        points.fail("expected a non-empty array");
      }
      for (std::size_t j = 0; j < points.value().size(); ++j) {
        ObjectIn point(JsonIn(points.value()[j], points.path() + "[" + std::to_string(j) + "]"));
        int threads = 0;
        double bytes_per_s = 0.0;
        point("threads", threads);
        point("bytes_per_s", bytes_per_s);
        point.finish();
        s.bytes_per_s.emplace_back(threads, bytes_per_s);
      }
      set.finish();
      try {
        BandwidthCurve check(s.bytes_per_s, 0.0);
      } catch (const std::invalid_argument& e) {
        points.fail(e.what());
      }
      if (!probe.working_sets.empty() && s.bytes <= probe.working_sets.back().bytes) {
        set.field("bytes").fail("working sets must be ascending by bytes");
      }
      probe.working_sets.push_back(std::move(s));
    }
    // Machine files from before the arithmetic probe have none.
    if (const std::optional<JsonIn> arithmetic = top.optional_field("arithmetic")) {
      if (!arithmetic->value().is_array()) arithmetic->fail("expected an array");
      for (std::size_t j = 0; j < arithmetic->value().size(); ++j) {
        ObjectIn point(
            JsonIn(arithmetic->value()[j], arithmetic->path() + "[" + std::to_string(j) + "]"));
        int threads = 0;
        double rate = 0.0;
        point("threads", threads);
        point("operations_per_s", rate);
        point.finish();
        if (threads < 1 || !(rate > 0.0)) {
          point.in().fail("threads must be >= 1 and operations_per_s > 0");
        }
        if (!probe.operations_per_s.empty() && threads <= probe.operations_per_s.back().first) {
          point.in().fail("thread counts must be ascending and distinct");
        }
        probe.operations_per_s.emplace_back(threads, rate);
      }
    }
    top.finish();
    return probe;
  } catch (const SchemaError& e) {
    throw InputError("machine file " + path + ": " + e.what());
  }
}

BandwidthCurve curve_of(const ProbedWorkingSet& set, double ceiling_bytes_per_s) {
  return BandwidthCurve(set.bytes_per_s, ceiling_bytes_per_s);
}

const ProbedWorkingSet& MemorySystem::working_set(std::uint64_t footprint_bytes) const {
  std::vector<std::uint64_t> sizes;
  for (const ProbedWorkingSet& set : probe.working_sets) sizes.push_back(set.bytes);
  return probe.working_sets[working_set_for(sizes, footprint_bytes)];
}

nlohmann::json MemorySystem::json() const {
  return {{"machine_file", machine_file},
          {"ceiling_bytes_per_s", ceiling_bytes_per_s},
          {"ceiling_source", ceiling_source}};
}

nlohmann::json MemorySystem::json(std::uint64_t footprint_bytes) const {
  nlohmann::json priced = json();
  priced["working_set_bytes"] = working_set(footprint_bytes).bytes;
  priced["footprint_bytes"] = footprint_bytes;
  return priced;
}

std::string MemorySystem::describe(std::uint64_t footprint_bytes) const {
  constexpr double kMiB = 1 << 20;
  return fmt::format(
      "{} ({:.0f} MiB working set for a {:.0f} MiB footprint); beyond the probed threads {}",
      machine_file, static_cast<double>(working_set(footprint_bytes).bytes) / kMiB,
      static_cast<double>(footprint_bytes) / kMiB,
      ceiling_bytes_per_s > 0
          ? fmt::format("towards {} GB/s ({})", ceiling_bytes_per_s / 1e9, ceiling_source)
          : std::string("the last probed bandwidth (no ceiling stated)"));
}

}  // namespace contactlab::tuner
