// The DEM halo over MPI (halo_exchange.hpp).
#include "contactlab/dem_mpi/halo_exchange.hpp"

#include <omp.h>

#include <algorithm>
#include <cstring>
#include <limits>
#include <unordered_set>
#include <utility>

#include "contactlab/mpi/runtime.hpp"
#include "particle_records.hpp"

namespace contactlab::dem::mpi {

namespace {

using contactlab::mpi::all_to_all_bytes;

template <class T>
void append(std::vector<char>& out, const T& value) {
  const char* at = reinterpret_cast<const char*>(&value);
  out.insert(out.end(), at, at + sizeof value);
}

template <class T>
T take(const char*& in) {
  T value;
  std::memcpy(&value, in, sizeof value);
  in += sizeof value;
  return value;
}

// What a ghost's owner sends after every force evaluation: all that the next drift and forces
// read and the step changes (the rest of its record came with it at the rebuild).
constexpr std::size_t kRefreshDoubles = 15;
constexpr int kRefreshTag = 41;

}  // namespace

HaloExchange::HaloExchange(MPI_Comm comm, Slabs slabs, double halo_width, double rebalance_margin)
    : comm_(comm),
      rank_(contactlab::mpi::rank_of(comm)),
      ranks_(contactlab::mpi::size_of(comm)),
      slabs_(std::move(slabs)),
      halo_width_(halo_width),
      rebalance_margin_(rebalance_margin) {
  const auto r = static_cast<std::size_t>(ranks_);
  send_ids_.resize(r);
  recv_ids_.resize(r);
  send_index_.resize(r);
  recv_index_.resize(r);
  send_buffer_.resize(r);
  recv_buffer_.resize(r);
}

double HaloExchange::max_over_ranks(double local) {
  if (ranks_ == 1) return local;  // every step: no call where there is nobody to agree with
  const double t0 = omp_get_wtime();
  double global = local;
  MPI_Allreduce(&local, &global, 1, MPI_DOUBLE, MPI_MAX, comm_);
  stats_.agreement_s += omp_get_wtime() - t0;
  return global;
}

double HaloExchange::sum_over_ranks(double local) {
  if (ranks_ == 1) return local;
  double global = local;
  MPI_Allreduce(&local, &global, 1, MPI_DOUBLE, MPI_SUM, comm_);
  return global;
}

Box HaloExchange::box_over_ranks(const Box& local) {
  // One reduction: the lows negated, so that the largest of every entry is wanted.
  double mine[6] = {-local.lo[0], -local.lo[1], -local.lo[2],
                    local.hi[0],  local.hi[1],  local.hi[2]};
  double all[6];
  MPI_Allreduce(mine, all, 6, MPI_DOUBLE, MPI_MAX, comm_);
  Box box;
  for (int a = 0; a < 3; ++a) {
    box.lo[a] = -all[a];
    box.hi[a] = all[3 + a];
  }
  return box;
}

void HaloExchange::drop_ghosts(Particles& particles, PairList& pairs, CarriedSprings& carried) {
  collect_springs(particles, pairs, carried);
  if (seeds_.size() > 0) {
    carried.keys.insert(carried.keys.end(), seeds_.keys.begin(), seeds_.keys.end());
    carried.springs.insert(carried.springs.end(), seeds_.springs.begin(), seeds_.springs.end());
    seeds_.clear();
  }
  // The owned particles' work as the list that ends here weighs it (slabs.hpp's measure), by
  // id: the sink may take some before the re-balancing reads it.
  std::vector<double> work(particles.size(), 1.0);
  for (std::size_t k = 0; k < pairs.size(); ++k) {
    work[pairs.i[k]] += 0.5;
    work[pairs.j[k]] += 0.5;
  }
  work_of_id_.clear();
  for (std::size_t a = 0; a < particles.size(); ++a) {
    if (a >= ghost_.size() || ghost_[a] == 0) work_of_id_.emplace(particles.id[a], work[a]);
  }
  if (owned_ < ghost_.size()) {
    std::vector<std::uint8_t> keep(ghost_.size());
    for (std::size_t a = 0; a < keep.size(); ++a) keep[a] = ghost_[a] == 0 ? 1 : 0;
    keep_particles(particles, keep);
  }
  pairs.resize(0);
  ghost_.assign(particles.size(), 0);
  owned_ = particles.size();
}

void HaloExchange::rebalance(const Particles& p) {
  std::vector<double> work(p.size());
  double local = 0.0;
  for (std::size_t k = 0; k < p.size(); ++k) {
    const auto found = work_of_id_.find(p.id[k]);
    work[k] = found != work_of_id_.end() ? found->second : 1.0;
    local += work[k];
  }
  double reduced[2];  // the work summed over the ranks, and the largest rank's
  MPI_Allreduce(&local, &reduced[0], 1, MPI_DOUBLE, MPI_SUM, comm_);
  MPI_Allreduce(&local, &reduced[1], 1, MPI_DOUBLE, MPI_MAX, comm_);
  const double mean = reduced[0] / ranks_;
  const double imbalance = mean > 0.0 ? reduced[1] / mean : 1.0;
  stats_.imbalance_sum += imbalance;
  stats_.imbalance_max = std::max(stats_.imbalance_max, imbalance);
  ++stats_.imbalance_samples;
  if (!(imbalance > 1.0 + rebalance_margin_) || mean <= 0.0) return;
  // New cuts from a histogram of the work along the axis (kBins bins over the particles'
  // extent, reduced over the ranks: O(kBins) per rank, whatever N is), each cut where the
  // running work crosses r W / R, interpolated within its bin.
  constexpr int kBins = 4096;
  const auto& c = p.coordinate(slabs_.axis);
  double extent[2] = {std::numeric_limits<double>::infinity(),
                      std::numeric_limits<double>::infinity()};  // -min, max
  for (const double v : c) {
    const double w = slabs_.wrap(v);
    extent[0] = std::min(extent[0], w);
    extent[1] = std::min(extent[1], -w);
  }
  double all[2];
  MPI_Allreduce(extent, all, 2, MPI_DOUBLE, MPI_MIN, comm_);
  const double lo = all[0], hi = -all[1];
  const double width = hi > lo ? (hi - lo) / kBins : 1.0;
  std::vector<double> histogram(kBins, 0.0), total(kBins, 0.0);
  for (std::size_t k = 0; k < c.size(); ++k) {
    const auto bin = std::clamp(static_cast<int>((slabs_.wrap(c[k]) - lo) / width), 0, kBins - 1);
    histogram[static_cast<std::size_t>(bin)] += work[k];
  }
  MPI_Allreduce(histogram.data(), total.data(), kBins, MPI_DOUBLE, MPI_SUM, comm_);
  double running = 0.0;
  int bin = 0;
  for (int r = 1; r < ranks_; ++r) {
    const double target = reduced[0] * r / ranks_;
    while (bin < kBins && running + total[bin] <= target) running += total[bin++];
    const double fraction = bin < kBins && total[bin] > 0 ? (target - running) / total[bin] : 0;
    slabs_.cuts[r] = std::max(slabs_.cuts[r - 1], lo + width * (bin + fraction));
  }
  ++stats_.rebalances;
}

void HaloExchange::exchange_particles(Particles& p, CarriedSprings& carried) {
  const double t0 = omp_get_wtime();
  if (ranks_ > 1) rebalance(p);
  const auto rank_count = static_cast<std::size_t>(ranks_);
  const std::size_t record = record_bytes(p);
  // 1. Migration: the particles whose slab changed, each with the springs of all its contacts
  //    (this rank owned it, so it computed every one of them). Message to rank r: count,
  //    records, spring count, (key, spring) entries.
  const auto& c = p.coordinate(slabs_.axis);
  std::vector<std::vector<char>> bytes(rank_count);
  std::vector<std::uint8_t> keep(p.size(), 1);
  std::unordered_map<std::uint32_t, int> leaving;  // id -> its new owner
  std::vector<std::uint64_t> leaving_count(rank_count, 0);
  for (std::size_t k = 0; k < p.size(); ++k) {
    const int owner = slabs_.owner(c[k]);
    if (owner == rank_) continue;
    keep[k] = 0;
    leaving.emplace(p.id[k], owner);
    ++leaving_count[owner];
  }
  for (std::size_t r = 0; r < rank_count; ++r) {
    if (leaving_count[r] > 0) append(bytes[r], leaving_count[r]);
  }
  for (std::size_t k = 0; k < p.size(); ++k) {
    if (keep[k] == 0) append_record(p, k, bytes[leaving.at(p.id[k])]);
  }
  if (!leaving.empty()) {
    std::vector<std::vector<std::uint64_t>> spring_index(rank_count);
    for (std::size_t s = 0; s < carried.size(); ++s) {
      const auto lo = static_cast<std::uint32_t>(carried.keys[s] >> 32);
      const auto hi = static_cast<std::uint32_t>(carried.keys[s] & 0xffffffffu);
      const auto a = leaving.find(lo), b = leaving.find(hi);
      if (a != leaving.end()) spring_index[a->second].push_back(s);
      if (b != leaving.end() && (a == leaving.end() || a->second != b->second))
        spring_index[b->second].push_back(s);
    }
    for (std::size_t r = 0; r < rank_count; ++r) {
      if (leaving_count[r] == 0) continue;
      append(bytes[r], static_cast<std::uint64_t>(spring_index[r].size()));
      for (const std::uint64_t s : spring_index[r]) {
        append(bytes[r], carried.keys[s]);
        for (int d = 0; d < 3; ++d) append(bytes[r], carried.springs[3 * s + d]);
      }
      stats_.migrated += leaving_count[r];
      stats_.migrated_springs += spring_index[r].size();
    }
    keep_particles(p, keep);
  }
  std::vector<std::uint64_t> counts;
  const std::vector<char> arrived = all_to_all_bytes(comm_, bytes, &counts);
  if (!arrived.empty()) {
    std::unordered_set<std::uint32_t> arrivals;
    CarriedSprings theirs;
    const char* in = arrived.data();
    for (std::size_t r = 0; r < rank_count; ++r) {
      if (counts[r] == 0) continue;
      const auto n = take<std::uint64_t>(in);
      for (std::uint64_t k = 0; k < n; ++k) {
        in += read_record(in, p);
        arrivals.insert(p.id.back());
      }
      const auto springs = take<std::uint64_t>(in);
      for (std::uint64_t s = 0; s < springs; ++s) {
        const auto key = take<std::uint64_t>(in);
        const auto sx = take<double>(in), sy = take<double>(in), sz = take<double>(in);
        theirs.add(key, sx, sy, sz);
      }
    }
    // The arrivals' springs are their old owners' (this rank may hold stale ones of pairs it
    // saw only between two ghosts): every spring with an arrival is replaced.
    std::size_t kept = 0;
    for (std::size_t s = 0; s < carried.size(); ++s) {
      const auto lo = static_cast<std::uint32_t>(carried.keys[s] >> 32);
      const auto hi = static_cast<std::uint32_t>(carried.keys[s] & 0xffffffffu);
      if (arrivals.contains(lo) || arrivals.contains(hi)) continue;
      carried.keys[kept] = carried.keys[s];
      std::copy_n(&carried.springs[3 * s], 3, &carried.springs[3 * kept]);
      ++kept;
    }
    carried.keys.resize(kept);
    carried.springs.resize(3 * kept);
    carried.keys.insert(carried.keys.end(), theirs.keys.begin(), theirs.keys.end());
    carried.springs.insert(carried.springs.end(), theirs.springs.begin(), theirs.springs.end());
  }

  // 2. Ghosts: every owned particle within the halo width of another rank's slab, its whole
  //    record to that rank; each step after this, its refresh in the same order.
  owned_ = p.size();
  const auto& pos = p.coordinate(slabs_.axis);
  for (std::size_t r = 0; r < rank_count; ++r) {
    bytes[r].clear();
    send_ids_[r].clear();
    recv_ids_[r].clear();
  }
  std::vector<int> near;
  for (std::size_t k = 0; k < owned_; ++k) {
    near.clear();
    slabs_.ranks_within(pos[k], halo_width_, rank_, near);
    for (const int r : near) {
      append_record(p, k, bytes[r]);
      send_ids_[r].push_back(p.id[k]);
    }
  }
  const std::vector<char> ghosts = all_to_all_bytes(comm_, bytes, &counts);
  const char* in = ghosts.data();
  for (std::size_t r = 0; r < rank_count; ++r) {
    for (std::uint64_t k = 0; k < counts[r] / record; ++k) {
      in += read_record(in, p);
      recv_ids_[r].push_back(p.id.back());
    }
  }
  stats_.ghosts = p.size() - owned_;
  stats_.migration_s += omp_get_wtime() - t0;
}

void HaloExchange::index_ghosts(const Particles& p) {
  std::unordered_map<std::uint32_t, std::uint32_t> index_of;
  index_of.reserve(p.size());
  for (std::size_t a = 0; a < p.size(); ++a)
    index_of.emplace(p.id[a], static_cast<std::uint32_t>(a));
  ghost_.assign(p.size(), 0);
  exchanges_ = false;
  for (std::size_t r = 0; r < send_ids_.size(); ++r) {
    exchanges_ = exchanges_ || !send_ids_[r].empty() || !recv_ids_[r].empty();
    send_index_[r].resize(send_ids_[r].size());
    for (std::size_t k = 0; k < send_ids_[r].size(); ++k)
      send_index_[r][k] = index_of.at(send_ids_[r][k]);
    recv_index_[r].resize(recv_ids_[r].size());
    for (std::size_t k = 0; k < recv_ids_[r].size(); ++k) {
      recv_index_[r][k] = index_of.at(recv_ids_[r][k]);
      ghost_[recv_index_[r][k]] = 1;
    }
    send_buffer_[r].resize(kRefreshDoubles * send_ids_[r].size());
    recv_buffer_[r].resize(kRefreshDoubles * recv_ids_[r].size());
  }
}

void HaloExchange::refresh_ghosts(Particles& p) {
  const double t0 = omp_get_wtime();
  double* const fields[kRefreshDoubles] = {p.x.data(),  p.y.data(),  p.z.data(),  p.vx.data(),
                                           p.vy.data(), p.vz.data(), p.wx.data(), p.wy.data(),
                                           p.wz.data(), p.fx.data(), p.fy.data(), p.fz.data(),
                                           p.tx.data(), p.ty.data(), p.tz.data()};
  requests_.clear();
  for (std::size_t r = 0; r < recv_index_.size(); ++r) {
    if (recv_index_[r].empty()) continue;
    requests_.emplace_back();
    MPI_Irecv(recv_buffer_[r].data(), static_cast<int>(recv_buffer_[r].size()), MPI_DOUBLE,
              static_cast<int>(r), kRefreshTag, comm_, &requests_.back());
  }
  for (std::size_t r = 0; r < send_index_.size(); ++r) {
    if (send_index_[r].empty()) continue;
    double* out = send_buffer_[r].data();
    for (const std::uint32_t k : send_index_[r]) {
      for (double* field : fields) *out++ = field[k];
    }
    requests_.emplace_back();
    MPI_Isend(send_buffer_[r].data(), static_cast<int>(send_buffer_[r].size()), MPI_DOUBLE,
              static_cast<int>(r), kRefreshTag, comm_, &requests_.back());
  }
  stats_.messages += requests_.size();
  MPI_Waitall(static_cast<int>(requests_.size()), requests_.data(), MPI_STATUSES_IGNORE);
  for (std::size_t r = 0; r < recv_index_.size(); ++r) {
    const double* in = recv_buffer_[r].data();
    for (const std::uint32_t k : recv_index_[r]) {
      for (double* field : fields) field[k] = *in++;
    }
  }
  ++stats_.refreshes;
  stats_.refresh_s += omp_get_wtime() - t0;
}

}  // namespace contactlab::dem::mpi
