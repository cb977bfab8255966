// Neighbour-list rebuild: periodic ghosts, the shared traversal, reorder by cell, history merge.
#include "contactlab/dem/pair_list.hpp"

#include <omp.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <span>
#include <string>
#include <utility>

#include "contactlab/kernels/count_then_fill.hpp"
#include "contactlab/kernels/error.hpp"
#include "contactlab/kernels/variant.hpp"

namespace contactlab::dem {

std::uint64_t spring_key(std::uint32_t a, std::uint32_t b) {
  return a < b ? (std::uint64_t{a} << 32 | b) : (std::uint64_t{b} << 32 | a);
}

void collect_springs(const Particles& p, const PairList& pairs, CarriedSprings& out, int threads) {
  auto touching = [&](std::size_t k) {
    return pairs.hx[k] != 0.0 || pairs.hy[k] != 0.0 || pairs.hz[k] != 0.0;
  };
  // In pair order, whatever the team.
  count_then_fill(
      pairs.size(), threads,
      [&](std::size_t first, std::size_t last) {
        std::size_t mine = 0;
        for (std::size_t k = first; k < last; ++k) mine += touching(k);
        return mine;
      },
      [&](std::size_t total) {
        resize_to_overwrite(out.keys, total);
        resize_to_overwrite(out.springs, 3 * total);
      },
      [&](std::size_t first, std::size_t last, std::size_t at) {
        for (std::size_t k = first; k < last; ++k) {
          if (!touching(k)) continue;
          const std::uint32_t a = p.id[pairs.i[k]], b = p.id[pairs.j[k]];
          const double sign = a < b ? 1.0 : -1.0;  // seen from i: turned to the lower id's view
          out.keys[at] = spring_key(a, b);
          out.springs[3 * at] = sign * pairs.hx[k];
          out.springs[3 * at + 1] = sign * pairs.hy[k];
          out.springs[3 * at + 2] = sign * pairs.hz[k];
          ++at;
        }
      });
}

RebuildStats NeighborBuilder::rebuild(Particles& p, PairList& pairs, const Domain& domain,
                                      double skin, int threads, RankAgreement* ranks,
                                      CarriedSprings* carried) {
  const std::size_t n = p.size();
  RebuildStats stats;
  // 1. The springs to carry. Where the old list indexes these particles, with its rows (the
  //    engine's own rebuilds), each new pair looks its spring up in its later particle's old row
  //    (4.): a few pairs each, in nearly the order of the new list, and no sort. Otherwise (a
  //    halo's migrants, the springs the sink took before it removed particles, a caller's list
  //    without rows) the touching pairs' springs, keyed by stable ids (oriented from the lower
  //    id), are merged by sorted keys (5.).
  const bool from_old_rows = carried == nullptr && n > 0 && pairs.rows.size() == n + 1;
  if (carried == nullptr && !from_old_rows) {
    collect_springs(p, pairs, old_springs_, threads);
    carried = &old_springs_;
  }

  // 2. Wrap periodic positions, and add ghosts: images within reach of a periodic face.
  double max_r = 0.0;
  const double* const radius = p.radius.data();
#pragma omp parallel for schedule(static) num_threads(threads) reduction(max : max_r)
  for (std::size_t k = 0; k < n; ++k) max_r = std::max(max_r, radius[k]);
  if (ranks != nullptr) max_r = ranks->max_over_ranks(max_r);
  const double reach = 2.0 * max_r + skin;
  for (int a = 0; a < 3; ++a) {
    if (!domain.periodic[a]) continue;
    if (domain.length(a) < 3.0 * reach) {
      throw InputError("periodic length along axis " + std::to_string(a) + " (" +
                       number_text(domain.length(a)) + " m) is under 3 pair reaches (" +
                       number_text(3.0 * reach) + " m)");
    }
    auto& c = a == 0 ? p.x : a == 1 ? p.y : p.z;
    const double lo = domain.lo[a], len = domain.length(a);
#pragma omp parallel for schedule(static) num_threads(threads)
    for (std::size_t k = 0; k < n; ++k) {
      const double wrapped = c[k] - len * std::floor((c[k] - lo) / len);
      c[k] = wrapped < domain.hi[a] ? wrapped : lo;
    }
  }
  // Displacements are measured from here on.
  for (auto* v : {&p.x0, &p.y0, &p.z0}) v->resize(n);
#pragma omp parallel for schedule(static) num_threads(threads)
  for (std::size_t k = 0; k < n; ++k) {
    p.x0[k] = p.x[k];
    p.y0[k] = p.y[k];
    p.z0[k] = p.z[k];
  }
  for (int a = 0; a < 3; ++a) {
    std::array<double, 3> s{0, 0, 0};
    s[a] = domain.length(a);
    for (int code = 0; code < 27; ++code) {
      const int im = a == 0 ? code % 3 : a == 1 ? (code / 3) % 3 : code / 9;
      pairs.shift[code][a] = (im - 1) * s[a];
    }
  }
  // The scene's rows in stable-id order (by_id_[row] = particle), so that the cell order's
  // ties and every row's partners follow the ids, not the order the particles came in.
  resize_to_overwrite(by_id_, n);
  resize_to_overwrite(sort_.keys, n);
  std::uint32_t max_id = 0;
#pragma omp parallel for schedule(static) num_threads(threads) reduction(max : max_id)
  for (std::size_t k = 0; k < n; ++k) {
    sort_.keys[k] = p.id[k];
    by_id_[k] = static_cast<std::uint32_t>(k);
    max_id = std::max(max_id, p.id[k]);
  }
  radix_sort(sort_.keys, by_id_, std::max(1, static_cast<int>(std::bit_width(max_id))),
             sort_.key_scratch, sort_.payload_scratch, threads);
  scene_.x.resize(n);
  scene_.y.resize(n);
  scene_.z.resize(n);
  scene_.diameter.resize(n);
#pragma omp parallel for schedule(static) num_threads(threads)
  for (std::size_t r = 0; r < n; ++r) {
    const std::uint32_t k = by_id_[r];
    scene_.x[r] = p.x[k];
    scene_.y[r] = p.y[k];
    scene_.z[r] = p.z[k];
    scene_.diameter[r] = 2.0 * p.radius[k];
  }
  // Row r's images within reach of a periodic face, in a fixed order (x, then y, then z
  // choices): emit(ix, iy, iz), the image's shift in box lengths, for each.
  const bool any_periodic = domain.periodic[0] || domain.periodic[1] || domain.periodic[2];
  auto each_ghost = [&](std::size_t r, auto&& emit) {
    const double pos[3] = {scene_.x[r], scene_.y[r], scene_.z[r]};
    int options[3][2];  // per axis: the images to try (0 = none)
    int counts[3];
    for (int a = 0; a < 3; ++a) {
      counts[a] = 1;
      options[a][0] = 0;
      if (!domain.periodic[a]) continue;
      if (pos[a] - domain.lo[a] < reach)
        options[a][counts[a]++] = 1;
      else if (domain.hi[a] - pos[a] < reach)
        options[a][counts[a]++] = -1;
    }
    for (int ax = 0; ax < counts[0]; ++ax) {
      for (int ay = 0; ay < counts[1]; ++ay) {
        for (int az = 0; az < counts[2]; ++az) {
          if (ax == 0 && ay == 0 && az == 0) continue;
          emit(options[0][ax], options[1][ay], options[2][az]);
        }
      }
    }
  };
  // The ghosts follow the rows: counted per range of rows, then written in row order.
  count_then_fill(
      any_periodic ? n : 0, threads,
      [&](std::size_t first, std::size_t last) {
        std::size_t mine = 0;
        for (std::size_t r = first; r < last; ++r) each_ghost(r, [&](int, int, int) { ++mine; });
        return mine;
      },
      [&](std::size_t total) {
        for (auto* v : {&scene_.x, &scene_.y, &scene_.z, &scene_.diameter}) v->resize(n + total);
        ghost_owner_.resize(total);
        ghost_image_.resize(total);
      },
      [&](std::size_t first, std::size_t last, std::size_t at) {
        for (std::size_t r = first; r < last; ++r) {
          each_ghost(r, [&](int ix, int iy, int iz) {
            scene_.x[n + at] = scene_.x[r] + ix * domain.length(0);
            scene_.y[n + at] = scene_.y[r] + iy * domain.length(1);
            scene_.z[n + at] = scene_.z[r] + iz * domain.length(2);
            scene_.diameter[n + at] = scene_.diameter[r];
            ghost_owner_[at] = static_cast<std::uint32_t>(r);
            ghost_image_[at] = static_cast<std::uint8_t>((ix + 1) + 3 * (iy + 1) + 9 * (iz + 1));
            ++at;
          });
        }
      });
  stats.ghosts = ghost_owner_.size();
  Box box;
  for (int a = 0; a < 3; ++a) {
    const double* const c = (a == 0 ? scene_.x : a == 1 ? scene_.y : scene_.z).data();
    const std::size_t size = scene_.x.size();  // ghosts included
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
#pragma omp parallel for schedule(static) num_threads(threads) reduction(min                 \
                                                                         : lo) reduction(max \
                                                                                         : hi)
    for (std::size_t k = 0; k < size; ++k) {
      lo = std::min(lo, c[k]);
      hi = std::max(hi, c[k]);
    }
    box.lo[a] = lo;
    box.hi[a] = hi;
  }
  if (ranks != nullptr) box = ranks->box_over_ranks(box);
  for (int a = 0; a < 3; ++a) {
    box.lo[a] -= reach;
    box.hi[a] += reach;
  }
  scene_.box = box;

  // 3. Pairs within r_i + r_j + skin from the shared traversal, on the engine's threads: the
  //    particle loop with the full stencil gives each particle's row from one thread in the
  //    stencil's order, and the registration is the same for any thread count, so the list
  //    (and the new order) does not depend on the threads.
  // (The diameter counts only for a process left without particles: a scene without any has
  // no per-particle diameters.)
  DetectOptions options{parse_variant("particle/sorted/full/static"), 2.0 * max_r, threads,
                        nullptr};
  options.homes = HomeRange{0, static_cast<std::uint32_t>(n)};
  options.min_cell_width = reach;
  const ContactList list = detector_.neighbor_list(scene_, options, skin);

  // 4. The new order: the particles' rows in cell (slot) order.
  const std::span<const std::uint32_t> working_to_input = detector_.working_to_input();
  count_then_fill(
      working_to_input.size(), threads,
      [&](std::size_t first, std::size_t last) {
        std::size_t mine = 0;
        for (std::size_t w = first; w < last; ++w) mine += working_to_input[w] < n;
        return mine;
      },
      [&](std::size_t total) { resize_to_overwrite(row_order_, total); },
      [&](std::size_t first, std::size_t last, std::size_t at) {
        for (std::size_t w = first; w < last; ++w) {
          if (working_to_input[w] < n) row_order_[at++] = working_to_input[w];
        }
      });
  order_.resize(n);
  new_index_.resize(n);  // by scene row
  pair_start_.resize(n + 1);
  // A particle's pairs: its row's partners that are particles, and each periodic pair once,
  // from its lower row.
  auto kept = [&](std::uint32_t row, std::uint32_t q) {
    return q < n || ghost_owner_[q - n] > row;
  };
#pragma omp parallel for schedule(static) num_threads(threads)
  for (std::size_t a = 0; a < n; ++a) {
    const std::uint32_t row = row_order_[a];
    order_[a] = by_id_[row];
    new_index_[row] = static_cast<std::uint32_t>(a);
    std::uint64_t count = 0;
    for (std::uint32_t q : list.partners_of(row)) count += kept(row, q);
    pair_start_[a + 1] = count;
  }
  p.permute(order_, threads);

  // The pairs in particle order, each thread filling the pairs of its particles from their
  // offsets (a parallel prefix sum over the counts).
  pair_start_[0] = 0;
  parallel_inclusive_scan(pair_start_.data() + 1, n, threads, range_sums_);
  const std::size_t count = pair_start_[n];
  if (from_old_rows) {  // the old list's rows, partners and springs, kept apart while it is read
    old_rows_.swap(pairs.rows);
    old_j_.swap(pairs.j);
    old_hx_.swap(pairs.hx);
    old_hy_.swap(pairs.hy);
    old_hz_.swap(pairs.hz);
  }
  // The old pair of the particles at old indices a (the new pair's i) and b, if it touched: its
  // spring seen from a into h (negated where the old pair ran from b: it was seen from its i,
  // the later of the two), as the keyed merge gives it.
  const std::uint32_t *const old_rows = old_rows_.data(), *const old_j = old_j_.data();
  const double *const old_hx = old_hx_.data(), *const old_hy = old_hy_.data(),
                      *const old_hz = old_hz_.data();
  auto old_spring = [=](std::uint32_t a, std::uint32_t b, double* h) {
    const std::uint32_t later = std::max(a, b), earlier = std::min(a, b);
    for (std::uint32_t m = old_rows[later]; m < old_rows[later + 1]; ++m) {
      if (old_j[m] != earlier) continue;
      if (old_hx[m] == 0.0 && old_hy[m] == 0.0 && old_hz[m] == 0.0) return false;
      const double sign = a == later ? 1.0 : -1.0;
      h[0] = sign * old_hx[m];
      h[1] = sign * old_hy[m];
      h[2] = sign * old_hz[m];
      return true;
    }
    return false;
  };
  pairs.resize_to_overwrite(count);
  std::size_t looked_up = 0;
#pragma omp parallel for schedule(static) num_threads(threads) reduction(+ : looked_up)
  for (std::size_t a = 0; a < n; ++a) {
    const std::uint32_t row = row_order_[a];
    std::uint64_t k = pair_start_[a];
    for (std::uint32_t q : list.partners_of(row)) {
      if (!kept(row, q)) continue;
      const std::uint32_t partner = q < n ? q : ghost_owner_[q - n];
      pairs.i[k] = static_cast<std::uint32_t>(a);
      pairs.j[k] = new_index_[partner];
      pairs.image[k] = q < n ? kNoImage : ghost_image_[q - n];
      double h[3] = {0.0, 0.0, 0.0};
      if (from_old_rows) looked_up += old_spring(by_id_[row], by_id_[partner], h);
      pairs.hx[k] = h[0];
      pairs.hy[k] = h[1];
      pairs.hz[k] = h[2];
      ++k;
    }
  }
  stats.pairs = count;
  stats.carried_contacts += looked_up;

  // 5. Merge the carried springs into the new list by sorted keys: O(pairs) radix sorts.
  if (!from_old_rows && carried->size() > 0) {
    std::vector<std::uint64_t>& old_keys = carried->keys;
    const std::size_t old_count = old_keys.size();
    resize_to_overwrite(old_payload_, old_count);
#pragma omp parallel for schedule(static) num_threads(threads) reduction(max : max_id)
    for (std::size_t k = 0; k < old_count; ++k) {
      old_payload_[k] = static_cast<std::uint32_t>(k);
      max_id = std::max<std::uint32_t>(max_id, static_cast<std::uint32_t>(old_keys[k]));
    }
    std::vector<std::uint64_t>& new_keys = sort_.keys;
    std::vector<std::uint32_t>& new_payload = sort_.payload;
    resize_to_overwrite(new_keys, count);
    resize_to_overwrite(new_payload, count);
#pragma omp parallel for schedule(static) num_threads(threads)
    for (std::size_t k = 0; k < count; ++k) {
      new_keys[k] = spring_key(p.id[pairs.i[k]], p.id[pairs.j[k]]);
      new_payload[k] = static_cast<std::uint32_t>(k);
    }
    const int id_bits = std::max(1, static_cast<int>(std::bit_width(max_id)));
    // Keys are lo << 32 | hi: sort the low id_bits of each half (two rounds over the key).
    auto sort_keys = [&](std::vector<std::uint64_t>& keys, std::vector<std::uint32_t>& payload) {
      const std::size_t size = keys.size();
#pragma omp parallel for schedule(static) num_threads(threads)
      for (std::size_t k = 0; k < size; ++k) {
        keys[k] = (keys[k] >> 32) << id_bits | (keys[k] & 0xffffffffu);
      }
      radix_sort(keys, payload, 2 * id_bits, sort_.key_scratch, sort_.payload_scratch, threads);
    };
    sort_keys(old_keys, old_payload_);
    sort_keys(new_keys, new_payload);
    // Each thread walks a range of the new keys from the first old key not below its first; a
    // range starts where a key differs from the one before it, so an equal key is matched once,
    // as one walk from the start would match it.
    auto range_edge = [&](std::size_t b) {
      while (b > 0 && b < count && new_keys[b] == new_keys[b - 1]) ++b;
      return b;
    };
    std::size_t carried_contacts = 0;
#pragma omp parallel num_threads(threads) reduction(+ : carried_contacts)
    {
      const auto t = static_cast<std::size_t>(omp_get_thread_num());
      const auto size = static_cast<std::size_t>(omp_get_num_threads());
      const std::size_t last = range_edge(count * (t + 1) / size);
      std::size_t b = range_edge(count * t / size);
      std::size_t a = b < last
                          ? static_cast<std::size_t>(
                                std::lower_bound(old_keys.begin(), old_keys.end(), new_keys[b]) -
                                old_keys.begin())
                          : old_count;
      while (a < old_count && b < last) {
        if (old_keys[a] < new_keys[b]) {
          ++a;
        } else if (new_keys[b] < old_keys[a]) {
          ++b;
        } else {
          const std::uint32_t k = new_payload[b];
          const double sign = p.id[pairs.i[k]] < p.id[pairs.j[k]] ? 1.0 : -1.0;
          const double* s = &carried->springs[3 * std::size_t{old_payload_[a]}];
          pairs.hx[k] = sign * s[0];
          pairs.hy[k] = sign * s[1];
          pairs.hz[k] = sign * s[2];
          ++carried_contacts;
          ++a;
          ++b;
        }
      }
    }
    stats.carried_contacts += carried_contacts;
  }
  pairs.build_csr(n, threads, sort_);
  return stats;
}

}  // namespace contactlab::dem
