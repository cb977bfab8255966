#include "contactlab/tuner_model/output_cost.hpp"

#include <algorithm>
#include <cmath>

namespace contactlab::tuner {

double output_seconds(std::span<const OutputCost> costs, const OutputEstimate& output,
                      int threads) {
  if (costs.empty() || output.entries == 0 || threads < 1) return 0.0;
  const OutputCost* chosen = nullptr;
  for (const OutputCost& c : costs) {
    if (c.threads <= threads && (!chosen || c.threads > chosen->threads)) chosen = &c;
  }
  if (!chosen) {
    chosen = &*std::min_element(costs.begin(), costs.end(),
                                [](const auto& a, const auto& b) { return a.threads < b.threads; });
  }
  const OutputCost& c = *chosen;
  double per_entry = c.low_seconds_per_entry;
  if (output.degree >= c.high_degree) {
    per_entry = c.high_seconds_per_entry;
  } else if (c.low_degree > 0.0 && output.degree > c.low_degree && c.high_degree > c.low_degree) {
    const double along =
        std::log(output.degree / c.low_degree) / std::log(c.high_degree / c.low_degree);
    per_entry += along * (c.high_seconds_per_entry - c.low_seconds_per_entry);
  }
  return static_cast<double>(output.entries) / threads * std::max(per_entry, 0.0);
}

}  // namespace contactlab::tuner
