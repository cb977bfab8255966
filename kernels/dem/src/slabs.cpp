// Slabs along one axis, balanced by work (slabs.hpp).
#include "contactlab/dem/slabs.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "contactlab/kernels/error.hpp"

namespace contactlab::dem {

double Slabs::wrap(double c) const {
  if (!periodic) return c;
  const double len = hi - lo;
  const double wrapped = c - len * std::floor((c - lo) / len);
  return wrapped < hi ? wrapped : lo;
}

int Slabs::owner(double c) const {
  const double w = wrap(c);
  // The last cut at or below w: slabs [cuts[r], cuts[r + 1]).
  const auto above = std::upper_bound(cuts.begin() + 1, cuts.end() - 1, w);
  return static_cast<int>(above - (cuts.begin() + 1));
}

void Slabs::ranks_within(double c, double halo, int self, std::vector<int>& out) const {
  const double w = wrap(c);
  const std::size_t first = out.size();
  auto add_range = [&](double from, double to) {  // slabs meeting [from, to]
    for (int r = owner(from); r < ranks() && cuts[r] <= to; ++r) {
      if (r == self || cuts[r] == cuts[r + 1]) continue;  // itself, or an empty slab
      if (std::find(out.begin() + static_cast<std::ptrdiff_t>(first), out.end(), r) == out.end())
        out.push_back(r);
    }
  };
  if (!periodic) {
    add_range(w - halo, w + halo);
    return;
  }
  const double len = hi - lo;
  // Within the period, and the images across its ends.
  add_range(std::max(lo, w - halo), std::min(std::nextafter(hi, lo), w + halo));
  if (w - halo < lo) add_range(w - halo + len, std::nextafter(hi, lo));
  if (w + halo >= hi) add_range(lo, w + halo - len);
}

Particles slab_particles(const Slabs& slabs, const Particles& particles, int rank) {
  Particles own = particles;
  const auto& c = particles.coordinate(slabs.axis);
  own.for_each_array([&](auto& v) {
    std::size_t kept = 0;
    for (std::size_t a = 0; a < v.size(); ++a) {
      if (slabs.owner(c[a]) == rank) v[kept++] = v[a];
    }
    v.resize(kept);
  });
  return own;
}

std::vector<double> particle_work(const Particles& particles, const PairList& pairs) {
  std::vector<double> work(particles.size(), 1.0);
  for (std::size_t k = 0; k < pairs.size(); ++k) {
    work[pairs.i[k]] += 0.5;
    work[pairs.j[k]] += 0.5;
  }
  return work;
}

Slabs balance_slabs(const Particles& particles, std::span<const double> work, int ranks, int axis,
                    const Domain& domain) {
  if (ranks < 1) throw InputError("ranks must be >= 1 (got " + std::to_string(ranks) + ")");
  if (axis < 0 || axis > 2) throw InputError("the slab axis must be x, y or z");
  Slabs slabs;
  slabs.axis = axis;
  slabs.periodic = domain.periodic[axis];
  slabs.lo = domain.lo[axis];
  slabs.hi = domain.hi[axis];
  const double inf = std::numeric_limits<double>::infinity();
  const auto& c = particles.coordinate(axis);
  const std::size_t n = c.size();
  std::vector<std::uint32_t> order(n);
  std::iota(order.begin(), order.end(), 0u);
  std::vector<double> wrapped(n);
  for (std::size_t k = 0; k < n; ++k) wrapped[k] = slabs.wrap(c[k]);
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
    return wrapped[a] < wrapped[b] || (wrapped[a] == wrapped[b] && a < b);
  });
  double total = 0.0;
  for (std::size_t k = 0; k < n; ++k) total += work[k];
  slabs.cuts.assign(static_cast<std::size_t>(ranks) + 1, 0.0);
  slabs.cuts.front() = slabs.periodic ? slabs.lo : -inf;
  slabs.cuts.back() = slabs.periodic ? slabs.hi : inf;
  double running = 0.0;
  std::size_t k = 0;
  for (int r = 1; r < ranks; ++r) {
    const double target = total * r / ranks;
    while (k < n && running + work[order[k]] <= target) running += work[order[k++]];
    // Halfway between the last particle below the target and the next one; past the particles,
    // at the last one's far side (the slabs after it are empty).
    double cut = k == 0  ? (n > 0 ? wrapped[order[0]] : slabs.cuts.front())
                 : k < n ? 0.5 * (wrapped[order[k - 1]] + wrapped[order[k]])
                         : std::nextafter(wrapped[order[n - 1]], inf);
    if (!std::isfinite(cut)) cut = slabs.periodic ? slabs.hi : 0.0;
    slabs.cuts[r] = std::max(cut, slabs.cuts[r - 1]);
  }
  return slabs;
}

int longest_axis(const Particles& particles, const Domain& domain) {
  int best = 2;
  double best_extent = -1.0;
  for (int a = 0; a < 3; ++a) {
    const auto& c = particles.coordinate(a);
    double extent = 0.0;
    if (domain.periodic[a]) {
      extent = domain.length(a);
    } else if (!c.empty()) {
      const auto [mn, mx] = std::minmax_element(c.begin(), c.end());
      extent = *mx - *mn;
    }
    if (extent > best_extent) {
      best = a;
      best_extent = extent;
    }
  }
  return best;
}

std::string axis_name(int axis) { return axis == 0 ? "x" : axis == 1 ? "y" : "z"; }

int parse_axis(const std::string& text) {
  if (text == "x") return 0;
  if (text == "y") return 1;
  if (text == "z") return 2;
  throw InputError("axis '" + text + "': give x, y or z");
}

SlabLoad slab_load(const Slabs& slabs, const Particles& particles, std::span<const double> work,
                   double halo) {
  const int ranks = slabs.ranks();
  SlabLoad load;
  load.particles.assign(ranks, 0);
  load.ghosts.assign(ranks, 0);
  load.work.assign(ranks, 0.0);
  const auto& c = particles.coordinate(slabs.axis);
  std::vector<int> near;
  for (std::size_t k = 0; k < c.size(); ++k) {
    const int r = slabs.owner(c[k]);
    ++load.particles[r];
    load.work[r] += work[k];
    near.clear();
    slabs.ranks_within(c[k], halo, r, near);
    for (const int g : near) ++load.ghosts[g];
  }
  double total = 0.0, largest = 0.0;
  for (const double w : load.work) {
    total += w;
    largest = std::max(largest, w);
  }
  load.imbalance = total > 0.0 ? largest / (total / ranks) : 1.0;
  return load;
}

SlabPlan plan_slabs(const Particles& particles, const EngineSettings& settings, int ranks,
                    int axis) {
  if (particles.size() == 0) throw InputError("no particles");
  double max_r = 0.0;
  for (const double r : particles.radius) max_r = std::max(max_r, r);
  const double skin = settings.skin > 0.0 ? settings.skin : 0.1 * 2.0 * max_r;
  Particles ordered = particles;  // the list reorders them
  PairList pairs;
  NeighborBuilder builder;
  builder.rebuild(ordered, pairs, settings.domain, skin, settings.threads);
  return plan_slabs(ordered, pairs, settings, ranks, axis);
}

SlabPlan plan_slabs(const Particles& particles, const PairList& pairs,
                    const EngineSettings& settings, int ranks, int axis) {
  if (particles.size() == 0) throw InputError("no particles");
  double max_r = 0.0;
  for (const double r : particles.radius) max_r = std::max(max_r, r);
  SlabPlan plan;
  plan.skin = settings.skin > 0.0 ? settings.skin : 0.1 * 2.0 * max_r;
  plan.halo = 2.0 * max_r + plan.skin;
  plan.pairs = pairs.size();
  const std::vector<double> work = particle_work(particles, pairs);
  if (axis < 0) axis = longest_axis(particles, settings.domain);
  plan.slabs = balance_slabs(particles, work, ranks, axis, settings.domain);
  plan.load = slab_load(plan.slabs, particles, work, plan.halo);
  return plan;
}

}  // namespace contactlab::dem
