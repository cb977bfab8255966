// The near pairs: a filter of the neighbour list by gap, in its order, on the caller's threads.
#include "contactlab/dem/near_pairs.hpp"

#include <algorithm>
#include <bit>
#include <utility>

#include "contactlab/kernels/count_then_fill.hpp"

namespace contactlab::dem {

namespace {
constexpr std::size_t kWord = 64;
// The bits of a word below bit b.
inline std::uint64_t below(unsigned b) { return (std::uint64_t{1} << b) - 1; }
}  // namespace

void NearPairs::build(const PairList& all, bool springs_in_all, const double* kin,
                      std::size_t stride, std::size_t particles, double margin_m, double hot_speed,
                      int threads) {
  // The hot particles, eight to a byte (each byte one thread's).
  const std::size_t bytes = (particles + 7) / 8;
  hot.assign(bytes + 1, 0);
  const double hot_sq = hot_speed * hot_speed;
  std::size_t hot_total = 0;
#pragma omp parallel for schedule(static) num_threads(threads) reduction(+ : hot_total)
  for (std::size_t b = 0; b < bytes; ++b) {
    unsigned bits = 0;
    for (std::size_t p = 8 * b; p < std::min(particles, 8 * b + 8); ++p) {
      const double* v = kin + stride * p + 4;
      bits |= static_cast<unsigned>(v[0] * v[0] + v[1] * v[1] + v[2] * v[2] > hot_sq) << (p % 8);
    }
    hot[b] = static_cast<std::uint8_t>(bits);
    hot_total += static_cast<std::size_t>(std::popcount(bits));
  }
  hot_count = hot_total;
  auto is_hot = [&](std::uint32_t p) { return ((hot[p / 8] >> (p % 8)) & 1u) != 0; };
  const std::size_t count = all.size();
  const std::size_t words = (count + kWord - 1) / kWord;
  next_taken_.resize(words);
  next_taken_before_.resize(words + 1);
  // The test over words of 64 pairs (so that a thread's range holds whole words), with no
  // branch on its outcome (near or not is a coin toss on a bed: 60 / 40); then the pairs taken
  // copied word by word, their bits visited in order. A hot particle's pairs are all taken.
  count_then_fill(
      words, threads,
      [&](std::size_t first, std::size_t last) {
        std::size_t taken = 0;
        for (std::size_t w = first; w < last; ++w) {
          std::uint64_t bits = 0;
          const std::size_t k0 = w * kWord, k1 = std::min(count, k0 + kWord);
          for (std::size_t k = k0; k < k1; ++k) {
            const double* ki = kin + stride * all.i[k];
            const double* kj = kin + stride * all.j[k];
            const auto& sh = all.shift[all.image[k]];
            const double dx = ki[0] - kj[0] - sh[0], dy = ki[1] - kj[1] - sh[1],
                         dz = ki[2] - kj[2] - sh[2];
            const double reach = ki[3] + kj[3] + margin_m;
            const bool is_near =
                (dx * dx + dy * dy + dz * dz < reach * reach) | is_hot(all.i[k]) | is_hot(all.j[k]);
            bits |= std::uint64_t{is_near} << (k - k0);
          }
          next_taken_[w] = bits;
          taken += static_cast<std::size_t>(std::popcount(bits));
        }
        return taken;
      },
      [&](std::size_t total) {
        next_.resize_to_overwrite(total);
        resize_to_overwrite(next_.m_star, total);
        resize_to_overwrite(next_.inv_kt, total);
        next_taken_before_[words] = static_cast<std::uint32_t>(total);
      },
      [&](std::size_t first, std::size_t last, std::size_t at) {
        for (std::size_t w = first; w < last; ++w) {
          next_taken_before_[w] = static_cast<std::uint32_t>(at);
          const std::uint64_t was = springs_in_all ? 0 : taken_[w];
          for (std::uint64_t bits = next_taken_[w]; bits != 0; bits &= bits - 1, ++at) {
            const auto b = static_cast<unsigned>(std::countr_zero(bits));
            const std::size_t k = w * kWord + b;
            next_.i[at] = all.i[k];
            next_.j[at] = all.j[k];
            next_.image[at] = all.image[k];
            next_.m_star[at] = all.m_star[k];
            next_.inv_kt[at] = all.inv_kt[k];
            if (springs_in_all) {
              next_.hx[at] = all.hx[k];
              next_.hy[at] = all.hy[k];
              next_.hz[at] = all.hz[k];
            } else if ((was >> b) & 1) {  // near before: its spring is in this list
              const std::size_t o = taken_before_[w] + std::popcount(was & below(b));
              next_.hx[at] = list.hx[o];
              next_.hy[at] = list.hy[o];
              next_.hz[at] = list.hz[o];
            } else {  // left out before: apart since, its spring zero
              next_.hx[at] = next_.hy[at] = next_.hz[at] = 0.0;
            }
          }
        }
      });
  next_.shift = all.shift;
  next_.index_rows(particles, threads);
  std::swap(list, next_);
  taken_.swap(next_taken_);
  taken_before_.swap(next_taken_before_);
  margin = margin_m;
  moved = 0.0;
  ++builds;
}

void NearPairs::write_back(PairList& all, int threads) const {
  const std::size_t count = all.size();
  const auto words = static_cast<std::ptrdiff_t>(taken_.size());
#pragma omp parallel for schedule(static) num_threads(threads)
  for (std::ptrdiff_t w = 0; w < words; ++w) {
    const auto word = static_cast<std::size_t>(w);
    const std::size_t k0 = word * kWord, k1 = std::min(count, k0 + kWord);
    std::size_t o = taken_before_[word];
    for (std::size_t k = k0; k < k1; ++k) {
      const bool near = (taken_[word] >> (k - k0)) & 1;
      all.hx[k] = near ? list.hx[o] : 0.0;
      all.hy[k] = near ? list.hy[o] : 0.0;
      all.hz[k] = near ? list.hz[o] : 0.0;
      o += near;
    }
  }
}

}  // namespace contactlab::dem
