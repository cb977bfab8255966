// Cache geometries for the cache simulation (cache_sim.hpp): the FX10's, this machine's, or one a
// user gives as custom:L1SIZE,WAYS,LINE:L2SIZE,WAYS,LINE, each checked to be one a set-associative
// cache can have.
#include <fmt/core.h>

#include <string>
#include <string_view>
#include <vector>

#include "contactlab/kernels/error.hpp"
#include "contactlab/tuner/cache_sim.hpp"
#include "contactlab/tuner/context.hpp"

namespace contactlab::tuner {
namespace {

bool is_power_of_two(std::uint64_t v) { return v != 0 && (v & (v - 1)) == 0; }

void validate_level(const std::string& geometry, const char* level, const CacheLevel& c) {
  auto fail = [&](const std::string& what) {
    throw InputError(fmt::format("cache geometry '{}': {} ({} B, {}-way, {} B lines): {}", geometry,
                                 level, c.size_bytes, c.associativity, c.line_bytes, what));
  };
  if (c.line_bytes < 16 || !is_power_of_two(static_cast<std::uint64_t>(c.line_bytes))) {
    fail("line size must be a power of two >= 16 bytes");
  }
  if (c.associativity < 1) fail("associativity must be >= 1");
  if (c.size_bytes <= static_cast<std::uint64_t>(c.line_bytes))
    fail("size must exceed the line size");
  if (static_cast<std::uint64_t>(c.associativity) >
      c.size_bytes / static_cast<std::uint64_t>(c.line_bytes)) {
    fail("associativity exceeds size / line size");
  }
  const std::uint64_t way_bytes = std::uint64_t(c.associativity) * std::uint64_t(c.line_bytes);
  if (c.size_bytes % way_bytes != 0 || !is_power_of_two(c.size_bytes / way_bytes)) {
    fail(fmt::format("set count size / (ways * line) = {} / {} is not a power of two", c.size_bytes,
                     way_bytes));
  }
}

std::uint64_t parse_size(std::string_view text, const std::string& whole) {
  std::uint64_t multiplier = 1;
  if (!text.empty() && (text.back() == 'K' || text.back() == 'k')) {
    multiplier = 1024;
    text.remove_suffix(1);
  } else if (!text.empty() && (text.back() == 'M' || text.back() == 'm')) {
    multiplier = std::uint64_t{1024} * 1024;
    text.remove_suffix(1);
  }
  if (text.empty() || text.size() > 12 ||
      text.find_first_not_of("0123456789") != std::string_view::npos) {
    throw InputError(fmt::format("cache geometry '{}': '{}' is not a size (bytes, or with K or M)",
                                 whole, text));
  }
  return std::stoull(std::string(text)) * multiplier;
}

int parse_int(std::string_view text, const std::string& whole) {
  if (text.empty() || text.size() > 9 ||
      text.find_first_not_of("0123456789") != std::string_view::npos) {
    throw InputError(
        fmt::format("cache geometry '{}': '{}' is not a positive integer", whole, text));
  }
  return std::stoi(std::string(text));
}

CacheLevel parse_level(std::string_view text, const std::string& whole) {
  std::vector<std::string_view> parts;
  std::size_t pos = 0;
  for (;;) {
    const auto comma = text.find(',', pos);
    parts.push_back(
        text.substr(pos, comma == std::string_view::npos ? std::string_view::npos : comma - pos));
    if (comma == std::string_view::npos) break;
    pos = comma + 1;
  }
  if (parts.size() != 3) {
    throw InputError(fmt::format("cache geometry '{}': '{}' must be SIZE,WAYS,LINE", whole, text));
  }
  return {parse_size(parts[0], whole), parse_int(parts[1], whole), parse_int(parts[2], whole)};
}

}  // namespace

CacheGeometry fx10_geometry() {
  CacheGeometry g;
  g.name = "fx10";
  g.l1 = {std::uint64_t{32} * 1024, 2, 128};
  g.l2 = {std::uint64_t{12} * 1024 * 1024, 24, 128};
  g.description =
      "Fujitsu FX10 (SPARC64 IXfx) approximation: L1D 32 KiB 2-way 128 B lines, shared L2 12 MiB "
      "24-way 128 B lines (as commonly cited, not checked against the hardware); no prefetch, "
      "LRU replacement, one core's view of the whole L2";
  g.approximation = true;
  return g;
}

CacheGeometry host_geometry() {
  const MachineInfo& m = machine_info();
  const CacheInfo* l1 = nullptr;
  const CacheInfo* l2 = nullptr;
  for (const auto& c : m.caches) {
    if (c.level == 1 && c.type == "data" && !l1) l1 = &c;
    if (c.level == 2 && c.type != "instruction" && !l2) l2 = &c;
  }
  if (!l1 || !l2) {
    throw InputError(
        fmt::format("cache geometry 'host': cannot read this machine's {} (topology from {})",
                    !l1 ? "L1 data cache" : "L2 cache", m.topology_source));
  }
  for (const CacheInfo* c : {l1, l2}) {
    if (c->associativity <= 0 || c->line_bytes <= 0) {
      throw InputError(
          fmt::format("cache geometry 'host': L{} associativity or line size unknown ({}-way, {} B "
                      "lines, from {}); "
                      "give it as custom:...",
                      c->level, c->associativity, c->line_bytes, m.topology_source));
    }
  }
  CacheGeometry g;
  g.name = "host";
  g.l1 = {l1->size_bytes, l1->associativity, l1->line_bytes};
  g.l2 = {l2->size_bytes, l2->associativity, l2->line_bytes};
  g.description = fmt::format(
      "this machine's L1D and L2 as read from {} ({}): L2 simulated as the last level, so L3 "
      "and prefetchers are not modelled",
      m.topology_source, m.cpu_model);
  g.approximation = true;
  validate_geometry(g);
  return g;
}

CacheGeometry parse_cache_geometry(std::string_view text) {
  const std::string whole(text);
  if (text == "fx10") return fx10_geometry();
  if (text == "host") return host_geometry();
  constexpr std::string_view kCustom = "custom:";
  if (text.substr(0, kCustom.size()) == kCustom) {
    const std::string_view rest = text.substr(kCustom.size());
    const auto colon = rest.find(':');
    if (colon == std::string_view::npos) {
      throw InputError(fmt::format(
          "cache geometry '{}': expected custom:L1SIZE,WAYS,LINE:L2SIZE,WAYS,LINE", whole));
    }
    CacheGeometry g;
    g.name = "custom";
    g.l1 = parse_level(rest.substr(0, colon), whole);
    g.l2 = parse_level(rest.substr(colon + 1), whole);
    g.description = "user-given geometry " + whole;
    g.approximation = true;
    validate_geometry(g);
    return g;
  }
  throw InputError(
      fmt::format("unknown cache geometry '{}' (expected host, fx10 or "
                  "custom:L1SIZE,WAYS,LINE:L2SIZE,WAYS,LINE)",
                  whole));
}

void validate_geometry(const CacheGeometry& g) {
  validate_level(g.name, "L1", g.l1);
  validate_level(g.name, "L2", g.l2);
  if (g.l2.size_bytes < g.l1.size_bytes) {
    throw InputError(fmt::format("cache geometry '{}': L2 ({} B) is smaller than L1 ({} B)", g.name,
                                 g.l2.size_bytes, g.l1.size_bytes));
  }
}

}  // namespace contactlab::tuner
