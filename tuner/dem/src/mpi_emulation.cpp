// The decomposed DEM step at other rank counts (mpi_emulation.hpp).
#include "contactlab/tuner_dem/mpi_emulation.hpp"

#include <algorithm>
#include <cmath>
#include <set>
#include <utility>

namespace contactlab::dem {

namespace {

double reduction_s(int ranks, const NetworkModel& network) {
  return ranks > 1 ? 2.0 * network.latency_s * std::ceil(std::log2(static_cast<double>(ranks)))
                   : 0.0;
}

// The particles' work as the slabs weigh it (slabs.hpp): the total, and the mean a particle.
std::pair<double, double> work_total_and_mean(const Particles& particles, const PairList& pairs) {
  double total = 0.0;
  for (const double w : particle_work(particles, pairs)) total += w;
  return {total, particles.size() > 0 ? total / static_cast<double>(particles.size()) : 0.0};
}

}  // namespace

std::vector<DemMpiPoint> emulate_dem_mpi_strong(const Particles& particles, const PairList& pairs,
                                                const EngineSettings& settings,
                                                const std::vector<int>& ranks, int axis,
                                                double seconds_per_work,
                                                const NetworkModel& network) {
  const auto [total, mean_work] = work_total_and_mean(particles, pairs);
  std::vector<DemMpiPoint> points;
  double one = 0.0;  // the step at one rank
  for (const int r : ranks) {
    const SlabPlan plan = plan_slabs(particles, pairs, settings, r, axis);
    // Per rank: the ranks it exchanges with and the ghosts it sends.
    std::vector<std::set<int>> partners(static_cast<std::size_t>(r));
    std::vector<std::uint64_t> sent(static_cast<std::size_t>(r), 0);
    const auto& c = particles.coordinate(plan.slabs.axis);
    std::vector<int> near;
    for (std::size_t k = 0; k < c.size(); ++k) {
      const int owner = plan.slabs.owner(c[k]);
      near.clear();
      plan.slabs.ranks_within(c[k], plan.halo, owner, near);
      for (const int g : near) {
        ++sent[owner];
        partners[owner].insert(g);
        partners[g].insert(owner);
      }
    }
    DemMpiPoint point;
    point.ranks = r;
    point.imbalance = plan.load.imbalance;
    for (int q = 0; q < r; ++q) {
      const double compute =
          seconds_per_work *
          (plan.load.work[q] + static_cast<double>(plan.load.ghosts[q]) * mean_work);
      const auto n = static_cast<double>(partners[q].size());
      const double bytes = kGhostBytes * static_cast<double>(sent[q] + plan.load.ghosts[q]);
      const double exchange = 2.0 * n * network.latency_s + bytes / network.bandwidth;
      if (compute + exchange > point.compute_s + point.exchange_s) {
        point.compute_s = compute;
        point.exchange_s = exchange;
      }
      point.ghosts_max = std::max(point.ghosts_max, plan.load.ghosts[q]);
      point.neighbours_max = std::max(point.neighbours_max, static_cast<int>(partners[q].size()));
    }
    point.reduction_s = reduction_s(r, network);
    point.step_s = point.compute_s + point.exchange_s + point.reduction_s;
    if (r == 1) one = point.step_s;
    points.push_back(point);
  }
  // Speed-ups against one rank (emulated at R = 1 when it is not in the list).
  if (one == 0.0) {
    one =
        emulate_dem_mpi_strong(particles, pairs, settings, {1}, axis, seconds_per_work, network)[0]
            .step_s;
  }
  for (DemMpiPoint& p : points) p.speedup = one / p.step_s;
  return points;
}

std::vector<DemMpiPoint> emulate_dem_mpi_weak(const Particles& particles, const PairList& pairs,
                                              const EngineSettings& settings,
                                              const std::vector<int>& ranks, int axis,
                                              double seconds_per_work,
                                              const NetworkModel& network) {
  const auto [total, mean_work] = work_total_and_mean(particles, pairs);
  const SlabPlan plan = plan_slabs(particles, pairs, settings, 1, axis);
  const auto& c = particles.coordinate(plan.slabs.axis);
  // A copy's neighbours hold as ghosts its particles within the halo of its two ends, and it
  // holds as many of theirs.
  double lo = 0.0, hi = 0.0;
  if (!c.empty()) {
    lo = *std::min_element(c.begin(), c.end());
    hi = *std::max_element(c.begin(), c.end());
  }
  std::uint64_t edge = 0;
  for (const double v : c) {
    if (v - lo < plan.halo) ++edge;
    if (hi - v < plan.halo) ++edge;
  }
  const double alone = seconds_per_work * total;
  std::vector<DemMpiPoint> points;
  for (const int r : ranks) {
    DemMpiPoint point;
    point.ranks = r;
    const std::uint64_t ghosts = r > 1 ? edge : 0;  // the middle copies': both ends
    point.compute_s = alone + seconds_per_work * static_cast<double>(ghosts) * mean_work;
    const double neighbours = r > 2 ? 2.0 : r == 2 ? 1.0 : 0.0;
    point.exchange_s = 2.0 * neighbours * network.latency_s +
                       kGhostBytes * 2.0 * static_cast<double>(ghosts) / network.bandwidth;
    point.reduction_s = reduction_s(r, network);
    point.step_s = point.compute_s + point.exchange_s + point.reduction_s;
    point.speedup = alone / point.step_s;  // the efficiency of a scaled-up run
    point.ghosts_max = ghosts;
    point.neighbours_max = static_cast<int>(neighbours);
    points.push_back(point);
  }
  return points;
}

}  // namespace contactlab::dem
