#include "contactlab/kernels/variant.hpp"

#include <algorithm>
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
constexpr NameTable<GridIndex, 3> kGridIndexes{
    {{GridIndex::kAuto, "auto"}, {GridIndex::kDense, "dense"}, {GridIndex::kHashed, "hashed"}}};
constexpr NameTable<ScheduleKind, 4> kScheduleKinds{{{ScheduleKind::kStatic, "static"},
                                                     {ScheduleKind::kDynamic, "dynamic"},
                                                     {ScheduleKind::kGuided, "guided"},
                                                     {ScheduleKind::kBalanced, "balanced"}}};

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
std::string_view to_string(GridIndex index) { return name_of(kGridIndexes, index); }

std::string to_string(const Schedule& schedule) {
  std::string text(to_string(schedule.kind));
  if (schedule.chunk > 0) {
    text += ',';
    text += std::to_string(schedule.chunk);
  }
  return text;
}

bool has_valid_chunk(const Schedule& schedule) {
  switch (schedule.kind) {
    case ScheduleKind::kStatic:
      return schedule.chunk >= 0;
    case ScheduleKind::kBalanced:
      return schedule.chunk == 0;
    case ScheduleKind::kDynamic:
    case ScheduleKind::kGuided:
      return schedule.chunk >= 1;
  }
  return false;
}

LoopKind parse_loop(std::string_view text) { return parse_name(kLoops, text, "loop"); }
Order parse_order(std::string_view text) { return parse_name(kOrders, text, "order"); }
Stencil parse_stencil(std::string_view text) { return parse_name(kStencils, text, "stencil"); }
Precision parse_precision(std::string_view text) {
  return parse_name(kPrecisions, text, "precision");
}

GridIndex parse_grid_index(std::string_view text) {
  return parse_name(kGridIndexes, text, "grid index");
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
    if (schedule.kind == ScheduleKind::kBalanced) {
      throw InputError("schedule '" + std::string(text) +
                       "': balanced takes no chunk size (one block of equal work per thread)");
    }
    if (value <= 0 || value > 1'000'000'000) {
      throw InputError("schedule '" + std::string(text) + "': chunk size must be >= 1");
    }
    schedule.chunk = static_cast<int>(value);
  } else if (schedule.kind != ScheduleKind::kStatic && schedule.kind != ScheduleKind::kBalanced) {
    schedule.chunk = 1;  // OpenMP's default chunk for dynamic and guided
  }
  return schedule;
}

namespace {

template <auto Member, auto Parse>
void parse_into(std::string_view text, Variant& into) {
  into.*Member = Parse(text);
}

template <auto Member>
std::string print_of(const Variant& variant) {
  return std::string(to_string(variant.*Member));
}

template <class Enum, std::size_t N>
std::vector<std::string_view> names_of(const NameTable<Enum, N>& table) {
  std::vector<std::string_view> names;
  for (const auto& entry : table) names.push_back(entry.second);
  return names;
}

const VariantAxis& axis_named(std::string_view name) {
  std::string names;
  for (const VariantAxis& axis : variant_axes()) {
    if (axis.name == name) return axis;
    names += (names.empty() ? "" : ", ") + std::string(axis.name);
  }
  throw InputError("unknown variant axis '" + std::string(name) + "' (choose " + names + ")");
}

}  // namespace

const std::vector<VariantAxis>& variant_axes() {
  static const std::vector<VariantAxis> axes{
      {"loop", "what one parallel iteration is", names_of(kLoops),
       "cell | particle: parallel over grid cells (paper Fig. 4) or particles (Fig. 5)", true,
       parse_into<&Variant::loop, parse_loop>, print_of<&Variant::loop>},
      {"order", "memory order of the particles during detection", names_of(kOrders),
       "unsorted | sorted | morton: input order, grouped by cell (paper), or by cell in Morton "
       "order",
       true, parse_into<&Variant::order, parse_order>, print_of<&Variant::order>},
      {"stencil", "which neighbour cells a home particle tests", names_of(kStencils),
       "full | half: 27 cells, or own + 13 forward cells (each pair tested once)", true,
       parse_into<&Variant::stencil, parse_stencil>, print_of<&Variant::stencil>},
      {"schedule", "OpenMP schedule of the parallel loop", names_of(kScheduleKinds),
       "static | static,k | dynamic,k | guided,k | balanced: k >= 1; static = block partition; "
       "balanced = a block per thread of equal estimated work",
       true, parse_into<&Variant::schedule, parse_schedule>,
       [](const Variant& v) { return to_string(v.schedule); }},
      {"precision", "arithmetic of the pair test", names_of(kPrecisions),
       "double | float: float is relative to the box corner (half the traffic, may misjudge "
       "near-ties)",
       false, parse_into<&Variant::precision, parse_precision>, print_of<&Variant::precision>},
      {"grid", "how a cell's particles are found", names_of(kGridIndexes),
       "auto | dense | hashed: a table entry per cell (<= 2^28 keys), a hash table over the "
       "occupied cells (memory ~ N), or the one use_hashed_index picks for the scene",
       false, parse_into<&Variant::grid, parse_grid_index>, print_of<&Variant::grid>},
  };
  return axes;
}

const std::vector<VariantRule>& variant_rules() {
  static const std::vector<VariantRule> rules{};
  return rules;
}

std::optional<std::string_view> broken_rule(const Variant& variant) {
  for (const VariantRule& rule : variant_rules()) {
    if (!rule.holds(variant)) return rule.description;
  }
  return std::nullopt;
}

std::string to_string(const Variant& v) {
  const Variant defaults;
  std::string text;
  for (const VariantAxis& axis : variant_axes()) {
    const std::string value = axis.print(v);
    if (!axis.positional && value == axis.print(defaults)) continue;
    if (!text.empty()) text += '/';
    // Precision keeps its older bare form ("/float"), which result files already hold.
    if (!axis.positional && axis.name != "precision") text += std::string(axis.name) + "=";
    text += value;
  }
  return text;
}

Variant parse_variant(std::string_view text) {
  const auto parts = split(text, '/');
  std::vector<std::string_view> positional, named;
  for (const auto part : parts) {
    (part.find('=') == std::string_view::npos && named.empty() ? positional : named)
        .push_back(part);
  }
  // Older form: a bare fifth part is the precision.
  if (positional.size() == 5) {
    named.insert(named.begin(), positional.back());
    positional.pop_back();
  }
  if (positional.size() < 3 || positional.size() > 4) {
    throw InputError("variant '" + std::string(text) +
                     "' must be loop/order/schedule or loop/order/stencil/schedule[/precision], "
                     "e.g. particle/sorted/static,200");
  }
  Variant variant;
  variant.loop = parse_loop(positional[0]);
  variant.order = parse_order(positional[1]);
  if (positional.size() == 4) variant.stencil = parse_stencil(positional[2]);
  variant.schedule = parse_schedule(positional.back());
  std::vector<std::string_view> seen;
  for (const auto part : named) {
    const auto eq = part.find('=');
    const std::string_view name = eq == std::string_view::npos ? "precision" : part.substr(0, eq);
    const VariantAxis& axis = axis_named(name);
    if (axis.positional || std::find(seen.begin(), seen.end(), name) != seen.end()) {
      throw InputError("variant '" + std::string(text) + "': axis '" + std::string(name) +
                       "' given twice");
    }
    seen.push_back(name);
    axis.parse(eq == std::string_view::npos ? part : part.substr(eq + 1), variant);
  }
  if (const auto rule = broken_rule(variant)) {
    throw InputError("variant '" + std::string(text) + "' breaks the rule: " + std::string(*rule));
  }
  return variant;
}

std::string variants_help() {
  std::string text =
      "Variants are written loop/order/stencil/schedule (loop/order/schedule = full stencil), "
      "then\nany other axis as name=value when it is not the default (precision also as a bare "
      "fifth part).\n";
  for (const VariantAxis& axis : variant_axes()) {
    text += "  " + std::string(axis.name) + std::string(10 - axis.name.size(), ' ') +
            std::string(axis.values_help) + "\n";
  }
  return text;
}

std::vector<Variant> enumerate(const VariantSpace& space) {
  std::vector<Variant> variants;
  for (const auto loop : space.loops) {
    for (const auto order : space.orders) {
      for (const auto stencil : space.stencils) {
        for (const auto& schedule : space.schedules) {
          for (const auto precision : space.precisions) {
            for (const auto grid : space.grids) {
              const Variant v{loop, order, stencil, schedule, precision, grid};
              if (!broken_rule(v)) variants.push_back(v);
            }
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
  space.grids = {GridIndex::kDense, GridIndex::kHashed};
  space.schedules.push_back({ScheduleKind::kStatic, 0});
  space.schedules.push_back({ScheduleKind::kBalanced, 0});
  for (const auto& entry : kScheduleKinds) {
    if (entry.first == ScheduleKind::kBalanced) continue;
    for (const int chunk : chunks) space.schedules.push_back({entry.first, chunk});
  }
  return space;
}

}  // namespace contactlab
