#include "contactlab/tuner_model/bandwidth.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace contactlab::tuner {

BandwidthCurve::BandwidthCurve(std::vector<std::pair<int, double>> measured,
                               double ceiling_bytes_per_s)
    : measured_(std::move(measured)), ceiling_(ceiling_bytes_per_s) {
  if (measured_.empty()) throw std::invalid_argument("bandwidth curve: no measured point");
  for (std::size_t i = 0; i < measured_.size(); ++i) {
    const auto [threads, bytes_per_s] = measured_[i];
    if (threads < 1) throw std::invalid_argument("bandwidth curve: a thread count below 1");
    if (!(bytes_per_s > 0.0) || !std::isfinite(bytes_per_s)) {
      throw std::invalid_argument(
          "bandwidth curve: a bandwidth that is not a positive number (at " +
          std::to_string(threads) + " threads)");
    }
    if (i > 0 && threads <= measured_[i - 1].first) {
      throw std::invalid_argument("bandwidth curve: thread counts not ascending and distinct");
    }
  }
  if (!(ceiling_ >= 0.0) || !std::isfinite(ceiling_)) {
    throw std::invalid_argument("bandwidth curve: the ceiling is not a number >= 0");
  }
}

double BandwidthCurve::at(int threads) const {
  if (threads < 1) throw std::invalid_argument("bandwidth curve: threads must be >= 1");
  const auto [first_p, first_b] = measured_.front();
  if (threads <= first_p) return first_b * threads / first_p;
  for (std::size_t i = 1; i < measured_.size(); ++i) {
    const auto [p1, b1] = measured_[i];
    if (threads == p1) return b1;  // exactly (b0 + (b1 - b0) need not round to b1)
    if (threads < p1) {
      const auto [p0, b0] = measured_[i - 1];
      return b0 + (b1 - b0) * (threads - p0) / (p1 - p0);
    }
  }
  const auto [last_p, last_b] = measured_.back();
  if (!(ceiling_ > last_b)) return last_b;
  const double k = last_p * (ceiling_ / last_b - 1.0);
  return ceiling_ * threads / (threads + k);
}

double roofline_seconds(double compute_s, double bytes, double bytes_per_s) {
  if (!(compute_s >= 0.0) || !(bytes >= 0.0)) {
    throw std::invalid_argument("roofline: a negative time or byte count");
  }
  if (!(bytes_per_s > 0.0)) throw std::invalid_argument("roofline: bandwidth must be > 0");
  return std::max(compute_s, bytes / bytes_per_s);
}

std::size_t working_set_for(const std::vector<std::uint64_t>& probed_bytes,
                            std::uint64_t footprint_bytes) {
  if (probed_bytes.empty()) throw std::invalid_argument("working set: no probed size");
  for (std::size_t i = 0; i < probed_bytes.size(); ++i) {
    if (probed_bytes[i] >= footprint_bytes) return i;
  }
  return probed_bytes.size() - 1;
}

}  // namespace contactlab::tuner
