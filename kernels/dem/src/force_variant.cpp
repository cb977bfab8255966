#include "contactlab/dem/force_variant.hpp"

#include <algorithm>
#include <array>

#include "contactlab/kernels/error.hpp"

namespace contactlab::dem {
namespace {

constexpr std::array<std::pair<Accumulation, std::string_view>, 4> kAccumulations{
    {{Accumulation::kOrdered, "ordered"},
     {Accumulation::kPerThread, "per-thread"},
     {Accumulation::kAtomic, "atomic"},
     {Accumulation::kFullList, "full-list"}}};

std::vector<std::string_view> split(std::string_view text, char separator) {
  std::vector<std::string_view> parts;
  for (std::size_t at = 0;;) {
    const std::size_t next = text.find(separator, at);
    parts.push_back(text.substr(at, next == std::string_view::npos ? next : next - at));
    if (next == std::string_view::npos) return parts;
    at = next + 1;
  }
}

}  // namespace

std::string_view to_string(Accumulation accumulation) {
  for (const auto& [value, name] : kAccumulations) {
    if (value == accumulation) return name;
  }
  return "?";
}

std::string to_string(const ForceVariant& variant) {
  std::string text(to_string(variant.accumulation));
  text += '/';
  text += to_string(variant.schedule);
  if (variant.serial_walls) text += "/walls=serial";
  if (variant.fused_update) text += "/update=fused";
  return text;
}

ForceVariant parse_force_variant(std::string_view text) {
  const std::string quoted = "force variant '" + std::string(text) + "'";
  const auto parts = split(text, '/');
  if (parts.size() < 2) {
    throw InputError(quoted + " must be ACCUMULATION/SCHEDULE[/walls=serial][/update=separate]");
  }
  ForceVariant variant;
  const auto found = std::find_if(kAccumulations.begin(), kAccumulations.end(),
                                  [&](const auto& entry) { return entry.second == parts[0]; });
  if (found == kAccumulations.end()) {
    throw InputError(quoted + ": accumulation '" + std::string(parts[0]) +
                     "' is not one of ordered, per-thread, atomic, full-list");
  }
  variant.accumulation = found->first;
  variant.schedule = parse_schedule(parts[1]);
  for (std::size_t k = 2; k < parts.size(); ++k) {
    if (parts[k] == "walls=serial") {
      variant.serial_walls = true;
    } else if (parts[k] == "walls=parallel") {
      variant.serial_walls = false;
    } else if (parts[k] == "update=separate") {
      variant.fused_update = false;
    } else if (parts[k] == "update=fused") {
      variant.fused_update = true;
    } else {
      throw InputError(quoted + ": part '" + std::string(parts[k]) +
                       "' is not walls=serial|parallel or update=separate|fused");
    }
  }
  if (const auto rule = broken_rule(variant)) throw InputError(quoted + ": " + std::string(*rule));
  return variant;
}

std::optional<std::string_view> broken_rule(const ForceVariant& variant) {
  if (variant.accumulation == Accumulation::kOrdered &&
      !(variant.schedule.kind == ScheduleKind::kStatic && variant.schedule.chunk == 0)) {
    return "ordered accumulation needs the static block partition (schedule 'static')";
  }
  if (variant.serial_walls && variant.fused_update) {
    return "serial walls cannot be fused into the update (drop update=fused)";
  }
  if (variant.fused_update && (variant.accumulation == Accumulation::kPerThread ||
                               variant.accumulation == Accumulation::kAtomic)) {
    return "update=fused needs ordered or full-list accumulation (per-thread and atomic sums are "
           "complete only after every pair)";
  }
  return std::nullopt;
}

bool thread_count_invariant(const ForceVariant& variant) {
  return variant.accumulation == Accumulation::kOrdered ||
         variant.accumulation == Accumulation::kFullList;
}

std::vector<ForceVariant> force_variants(const std::vector<int>& chunks) {
  std::vector<Schedule> schedules{{ScheduleKind::kStatic, 0}};
  for (const int chunk : chunks) {
    for (const ScheduleKind kind :
         {ScheduleKind::kStatic, ScheduleKind::kDynamic, ScheduleKind::kGuided}) {
      schedules.push_back({kind, chunk});
    }
  }
  std::vector<ForceVariant> variants;
  for (const auto& [accumulation, name] : kAccumulations) {
    for (const Schedule& schedule : schedules) {
      for (const bool fused : {false, true}) {
        const ForceVariant variant{accumulation, schedule, false, fused};
        if (!broken_rule(variant)) variants.push_back(variant);
      }
    }
  }
  variants.push_back({Accumulation::kPerThread, {ScheduleKind::kDynamic, 1}, true, false});
  return variants;
}

}  // namespace contactlab::dem
