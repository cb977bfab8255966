#include "contactlab/kernels/variant.hpp"

#include <array>
#include <charconv>

#include "contactlab/kernels/error.hpp"

namespace contactlab {
namespace {

template <class Enum, std::size_t N>
using NameTable = std::array<std::pair<Enum, std::string_view>, N>;

constexpr NameTable<LoopKind, 2> kLoops{
    {{LoopKind::kCell, "cell"}, {LoopKind::kParticle, "particle"}}};
constexpr NameTable<Order, 3> kOrders{
    {{Order::kUnsorted, "unsorted"}, {Order::kSorted, "sorted"}, {Order::kMorton, "morton"}}};
constexpr NameTable<Stencil, 2> kStencils{{{Stencil::kFull, "full"}, {Stencil::kHalf, "half"}}};
constexpr NameTable<Precision, 2> kPrecisions{
    {{Precision::kDouble, "double"}, {Precision::kFloat, "float"}}};
constexpr NameTable<ScheduleKind, 3> kScheduleKinds{{{ScheduleKind::kStatic, "static"},
                                                     {ScheduleKind::kDynamic, "dynamic"},
                                                     {ScheduleKind::kGuided, "guided"}}};

template <class Enum, std::size_t N>
std::string_view name_of(const NameTable<Enum, N>& table, Enum value) {
  for (const auto& [v, name] : table) {
    if (v == value) return name;
  }
  return "?";
}

template <class Enum, std::size_t N>
Enum parse_name(const NameTable<Enum, N>& table, std::string_view text, std::string_view what) {
  std::string choices;
  for (const auto& [v, name] : table) {
    if (name == text) return v;
    if (!choices.empty()) choices += ", ";
    choices += name;
  }
  throw InputError("unknown " + std::string(what) + " '" + std::string(text) + "' (choose " +
                   choices + ")");
}

std::vector<std::string_view> split(std::string_view text, char separator) {
  std::vector<std::string_view> parts;
  std::size_t start = 0;
  while (true) {
    const std::size_t at = text.find(separator, start);
    parts.push_back(text.substr(start, at == std::string_view::npos ? at : at - start));
    if (at == std::string_view::npos) return parts;
    start = at + 1;
  }
}

}  // namespace

std::string_view to_string(LoopKind loop) { return name_of(kLoops, loop); }
std::string_view to_string(Order order) { return name_of(kOrders, order); }
std::string_view to_string(Stencil stencil) { return name_of(kStencils, stencil); }
std::string_view to_string(ScheduleKind kind) { return name_of(kScheduleKinds, kind); }
std::string_view to_string(Precision precision) { return name_of(kPrecisions, precision); }

std::string to_string(const Schedule& schedule) {
  std::string text(to_string(schedule.kind));
  if (schedule.chunk > 0) {
    text += ',';
    text += std::to_string(schedule.chunk);
  }
  return text;
}

std::string to_string(const Variant& v) {
  std::string text = std::string(to_string(v.loop)) + "/" + std::string(to_string(v.order)) + "/" +
                     std::string(to_string(v.stencil)) + "/" + to_string(v.schedule);
  if (v.precision != Precision::kDouble) {
    text += '/';
    text += to_string(v.precision);
  }
  return text;
}

LoopKind parse_loop(std::string_view text) { return parse_name(kLoops, text, "loop"); }
Order parse_order(std::string_view text) { return parse_name(kOrders, text, "order"); }
Stencil parse_stencil(std::string_view text) { return parse_name(kStencils, text, "stencil"); }
Precision parse_precision(std::string_view text) {
  return parse_name(kPrecisions, text, "precision");
}

Schedule parse_schedule(std::string_view text) {
  const auto parts = split(text, ',');
  if (parts.size() > 2) {
    throw InputError("schedule '" + std::string(text) + "' must be KIND or KIND,CHUNK");
  }
  Schedule schedule;
  schedule.kind = parse_name(kScheduleKinds, parts[0], "schedule kind");
  if (parts.size() == 2) {
    const std::string_view chunk = parts[1];
    long long value = 0;
    const auto [end, ec] = std::from_chars(chunk.data(), chunk.data() + chunk.size(), value);
    if (chunk.empty() || ec != std::errc() || end != chunk.data() + chunk.size()) {
      throw InputError("schedule '" + std::string(text) + "': chunk size '" + std::string(chunk) +
                       "' is not an integer");
    }
    if (value <= 0 || value > 1'000'000'000) {
      throw InputError("schedule '" + std::string(text) + "': chunk size must be >= 1");
    }
    schedule.chunk = static_cast<int>(value);
  } else if (schedule.kind != ScheduleKind::kStatic) {
    schedule.chunk = 1;  // OpenMP's default chunk for dynamic and guided
  }
  return schedule;
}

Variant parse_variant(std::string_view text) {
  const auto parts = split(text, '/');
  if (parts.size() < 3 || parts.size() > 5) {
    throw InputError("variant '" + std::string(text) +
                     "' must be loop/order/schedule or loop/order/stencil/schedule[/precision], "
                     "e.g. particle/sorted/static,200");
  }
  Variant variant;
  variant.loop = parse_loop(parts[0]);
  variant.order = parse_order(parts[1]);
  variant.stencil = parts.size() >= 4 ? parse_stencil(parts[2]) : Stencil::kFull;
  variant.schedule = parse_schedule(parts.size() >= 4 ? parts[3] : parts[2]);
  if (parts.size() == 5) variant.precision = parse_precision(parts[4]);
  return variant;
}

std::vector<Variant> enumerate(const VariantSpace& space) {
  std::vector<Variant> variants;
  for (const auto loop : space.loops) {
    for (const auto order : space.orders) {
      for (const auto stencil : space.stencils) {
        for (const auto& schedule : space.schedules) {
          for (const auto precision : space.precisions) {
            variants.push_back(Variant{loop, order, stencil, schedule, precision});
          }
        }
      }
    }
  }
  return variants;
}

std::vector<Variant> paper_variants() {
  const Schedule block{ScheduleKind::kStatic, 0};
  return {
      {LoopKind::kParticle, Order::kUnsorted, Stencil::kFull, block,
       Precision::kDouble},                                                              // Table 2
      {LoopKind::kCell, Order::kUnsorted, Stencil::kFull, block, Precision::kDouble},    // Table 3
      {LoopKind::kParticle, Order::kSorted, Stencil::kFull, block, Precision::kDouble},  // Table 4
      {LoopKind::kCell, Order::kSorted, Stencil::kFull, block, Precision::kDouble},      // Table 5
      {LoopKind::kParticle,
       Order::kSorted,
       Stencil::kFull,
       {ScheduleKind::kStatic, 200},
       Precision::kDouble},  // Table 7
  };
}

VariantSpace all_variants(const std::vector<int>& chunks) {
  VariantSpace space;
  for (const auto& entry : kLoops) space.loops.push_back(entry.first);
  for (const auto& entry : kOrders) space.orders.push_back(entry.first);
  for (const auto& entry : kStencils) space.stencils.push_back(entry.first);
  space.precisions.clear();
  for (const auto& entry : kPrecisions) space.precisions.push_back(entry.first);
  space.schedules.push_back({ScheduleKind::kStatic, 0});
  for (const auto& entry : kScheduleKinds) {
    for (const int chunk : chunks) space.schedules.push_back({entry.first, chunk});
  }
  return space;
}

}  // namespace contactlab
