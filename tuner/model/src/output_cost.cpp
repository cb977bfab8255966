#include "contactlab/tuner_model/output_cost.hpp"

#include <algorithm>
#include <cmath>

namespace contactlab::tuner {

namespace {

// The point calibrated at the largest thread count not above `threads`, else the smallest.
const OutputCost& point_for(std::span<const OutputCost> costs, int threads) {
  const OutputCost* chosen = nullptr;
  for (const OutputCost& c : costs) {
    if (c.threads <= threads && (!chosen || c.threads > chosen->threads)) chosen = &c;
  }
  if (!chosen) {
    chosen = &*std::min_element(costs.begin(), costs.end(),
                                [](const auto& a, const auto& b) { return a.threads < b.threads; });
  }
  return *chosen;
}

}  // namespace

double output_seconds(std::span<const OutputCost> costs, const OutputEstimate& output,
                      int threads) {
  if (costs.empty() || output.entries == 0 || threads < 1) return 0.0;
  const OutputCost& c = point_for(costs, threads);
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

double exchange_factor(std::span<const OutputCost> costs, int threads) {
  if (costs.empty() || threads <= 1) return 1.0;
  const double p = threads;
  return 1.0 + std::max(point_for(costs, threads).exchange, 0.0) * (p - 1.0) / p;
}

double fit_exchange(double passing_s, double block_s, int threads) {
  if (threads <= 1 || !(passing_s > 0.0) || !(block_s > 0.0)) return 0.0;
  const double p = threads;
  return std::max(0.0, (passing_s / block_s - 1.0) * p / (p - 1.0));
}

}  // namespace contactlab::tuner
