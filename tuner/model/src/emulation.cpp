#include "contactlab/tuner_model/emulation.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace contactlab::tuner {

double AmdahlPhase::at(int threads) const {
  if (threads < 1) throw std::invalid_argument("AmdahlPhase: threads must be >= 1");
  return serial_s + parallel_s / threads;
}

AmdahlPhase AmdahlPhase::fit(double one_thread_s, int p, double p_threads_s) {
  if (p <= 1) throw std::invalid_argument("AmdahlPhase::fit: the second point needs p > 1");
  if (!(one_thread_s > 0.0) || !(p_threads_s > 0.0)) {
    throw std::invalid_argument("AmdahlPhase::fit: times must be > 0");
  }
  // t1 = s + q, tp = s + q / p  =>  q = (t1 - tp) p / (p - 1).
  const double parallel =
      std::clamp((one_thread_s - p_threads_s) * p / (p - 1.0), 0.0, one_thread_s);
  return {one_thread_s - parallel, parallel};
}

double ExchangePhase::at(int threads) const {
  if (threads < 1) throw std::invalid_argument("ExchangePhase: threads must be >= 1");
  const double p = threads;
  return work_s / p + exchange_s * (p - 1.0) / (p * p);
}

ExchangePhase ExchangePhase::fit(double one_thread_s, int p, double p_threads_s) {
  if (p <= 1) throw std::invalid_argument("ExchangePhase::fit: the second point needs p > 1");
  if (!(one_thread_s > 0.0) || !(p_threads_s > 0.0)) {
    throw std::invalid_argument("ExchangePhase::fit: times must be > 0");
  }
  // tp = t1 / p + x (p - 1) / p^2  =>  x = (tp - t1 / p) p^2 / (p - 1).
  const double q = p;
  return {one_thread_s, std::max(0.0, (p_threads_s - one_thread_s / q) * q * q / (q - 1.0))};
}

AnchoredLoop::AnchoredLoop(const PreparedWork& work, const MachineCosts& costs,
                           const Schedule& schedule, double one_thread_s)
    : work_(work), costs_(costs) {
  if (!(one_thread_s > 0.0)) throw std::invalid_argument("AnchoredLoop: one_thread_s must be > 0");
  const double replayed = simulate_schedule(work_, 1, schedule, costs_).makespan_seconds;
  scale_ = replayed > 0.0 ? one_thread_s / replayed : 1.0;
}

ScheduleOutcome AnchoredLoop::replay(int threads, const Schedule& schedule) const {
  ScheduleOutcome outcome = simulate_schedule(work_, threads, schedule, costs_);
  outcome.makespan_seconds *= scale_;
  for (ThreadShare& share : outcome.threads) share.seconds *= scale_;
  return outcome;
}

double AnchoredLoop::seconds(int threads, const Schedule& schedule) const {
  return replay(threads, schedule).makespan_seconds;
}

double relative_error(double emulated, double measured) {
  return measured != 0.0 ? (emulated - measured) / measured : 0.0;
}

double CommunicationModel::message_s(double bytes) const {
  return latency_s + bytes / bandwidth_bytes_per_s;
}

double CommunicationModel::collective_s(int ranks, double bytes) const {
  if (ranks <= 1) return 0.0;
  return std::ceil(std::log2(static_cast<double>(ranks))) * message_s(bytes);
}

RankWork replicated_rank_work(WorkView work, std::uint32_t block, int ranks, int rank) {
  if (block < 1) throw std::invalid_argument("replicated_rank_work: block must be >= 1");
  if (ranks < 1 || rank < 0 || rank >= ranks) {
    throw std::invalid_argument("replicated_rank_work: rank outside [0, ranks)");
  }
  RankWork mine;
  const std::uint64_t n = work.size();
  const std::uint64_t stride = std::uint64_t{block} * static_cast<std::uint64_t>(ranks);
  for (std::uint64_t start = std::uint64_t{block} * rank; start < n; start += stride) {
    const std::uint64_t end = std::min<std::uint64_t>(start + block, n);
    for (std::uint64_t i = start; i < end; ++i) {
      mine.tests.push_back(work.tests[i]);
      mine.homes.push_back(work.homes.empty() ? 1 : work.homes[i]);
      // A block continues nothing of this rank's: its first iteration builds (when it has a
      // home); within a block the loop's own flags hold.
      const bool builds = work.builds.empty() || work.builds[i] != 0 ||
                          (i == start && (work.homes.empty() || work.homes[i] > 0));
      mine.builds.push_back(builds ? 1 : 0);
    }
  }
  return mine;
}

namespace {

MpiPrediction slowest_of(const std::vector<double>& rank_s, MpiPrediction prediction) {
  const auto slowest = std::max_element(rank_s.begin(), rank_s.end());
  prediction.slowest_rank = static_cast<int>(slowest - rank_s.begin());
  prediction.rank_imbalance = imbalance(std::span<const double>(rank_s));
  return prediction;
}

}  // namespace

MpiPrediction predict_replicated(WorkView work, const MachineCosts& costs, double scale,
                                 std::uint32_t block, int ranks, int threads_per_rank,
                                 const Schedule& schedule, const CommunicationModel& network,
                                 double fixed_s) {
  // Every rank pays the fixed cost, also one with no block (more ranks than blocks).
  std::vector<double> rank_s(static_cast<std::size_t>(ranks), fixed_s);
  for (int r = 0; r < ranks; ++r) {
    const RankWork mine = replicated_rank_work(work, block, ranks, r);
    if (mine.tests.empty()) continue;
    rank_s[r] +=
        scale * simulate_schedule(mine.view(), threads_per_rank, schedule, costs).makespan_seconds;
  }
  MpiPrediction prediction;
  prediction.ranks = ranks;
  prediction.threads_per_rank = threads_per_rank;
  prediction.compute_s = *std::max_element(rank_s.begin(), rank_s.end());
  prediction.replay_compute_s = prediction.compute_s;
  prediction.communication_s = network.collective_s(ranks, 8.0);
  return slowest_of(rank_s, prediction);
}

MpiPrediction with_locality(MpiPrediction prediction, double factor, double fixed_s) {
  if (!(factor > 0.0)) throw std::invalid_argument("with_locality: factor must be > 0");
  prediction.replay_compute_s = prediction.compute_s;
  prediction.locality = factor;
  prediction.compute_s = fixed_s + factor * std::max(prediction.compute_s - fixed_s, 0.0);
  return prediction;
}

MpiPrediction predict_decomposed(std::span<const DecomposedRank> ranks, std::uint64_t total_work,
                                 double one_rank_s, int threads_per_rank, double thread_efficiency,
                                 double bytes_per_ghost, const CommunicationModel& network,
                                 double fixed_s) {
  if (ranks.empty()) throw std::invalid_argument("predict_decomposed: no ranks");
  if (total_work == 0) throw std::invalid_argument("predict_decomposed: total_work is 0");
  if (threads_per_rank < 1 || !(thread_efficiency > 0.0)) {
    throw std::invalid_argument("predict_decomposed: threads_per_rank >= 1, efficiency > 0");
  }
  const int count = static_cast<int>(ranks.size());
  // The counts of the exchange first (an all-to-all, ceil(log2 R) rounds of R/2 counts), then
  // each rank receives its ghosts, one message per source, and runs its loop.
  const double counts_s = network.collective_s(count, 8.0 * count / 2.0);
  std::vector<double> compute(ranks.size()), finish(ranks.size());
  for (std::size_t r = 0; r < ranks.size(); ++r) {
    compute[r] = fixed_s + (one_rank_s - fixed_s) * static_cast<double>(ranks[r].work) /
                               static_cast<double>(total_work) /
                               (threads_per_rank * thread_efficiency);
    const double halo_s = static_cast<double>(ranks[r].halo_sources) * network.latency_s +
                          static_cast<double>(ranks[r].halo_particles) * bytes_per_ghost /
                              network.bandwidth_bytes_per_s;
    finish[r] = halo_s + compute[r];
  }
  MpiPrediction prediction;
  prediction.ranks = count;
  prediction.threads_per_rank = threads_per_rank;
  prediction.compute_s = *std::max_element(compute.begin(), compute.end());
  prediction.replay_compute_s = prediction.compute_s;
  prediction.communication_s =
      counts_s + *std::max_element(finish.begin(), finish.end()) - prediction.compute_s;
  return slowest_of(compute, prediction);
}

}  // namespace contactlab::tuner
