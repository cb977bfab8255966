#include "contactlab/tuner_model/output_cost.hpp"

#include <algorithm>
#include <cmath>

namespace contactlab::tuner {

double output_seconds(std::span<const OutputCost> costs, std::uint64_t entries, int threads) {
  if (costs.empty() || entries == 0 || threads < 1) return 0.0;
  const OutputCost* chosen = nullptr;
  for (const OutputCost& c : costs) {
    if (c.threads <= threads && (!chosen || c.threads > chosen->threads)) chosen = &c;
  }
  if (!chosen) {
    chosen = &*std::min_element(costs.begin(), costs.end(),
                                [](const auto& a, const auto& b) { return a.threads < b.threads; });
  }
  const OutputCost& c = *chosen;
  const double bytes = output_bytes(entries);
  double per_entry = c.small_seconds_per_entry;
  if (bytes >= c.large_bytes) {
    per_entry = c.large_seconds_per_entry;
  } else if (c.small_bytes > 0.0 && bytes > c.small_bytes && c.large_bytes > c.small_bytes) {
    const double along = std::log(bytes / c.small_bytes) / std::log(c.large_bytes / c.small_bytes);
    per_entry += along * (c.large_seconds_per_entry - c.small_seconds_per_entry);
  }
  return static_cast<double>(entries) / threads * std::max(per_entry, 0.0);
}

}  // namespace contactlab::tuner
