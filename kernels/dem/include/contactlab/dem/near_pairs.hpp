// The pairs of the neighbour list near enough to touch before the next check: what the force
// pass runs on. The neighbour list holds every pair within r_i + r_j + skin, so that it lasts
// until some particle has moved skin/2; on a settled bed 40 % of its pairs are apart, and the
// law on eight lanes costs an apart pair what it costs a contact (its outputs are zero). The
// near pairs are those whose gap is under a margin well below the skin, chosen again from the
// neighbour list (no cell search, no reorder) whenever the particles may have closed it: no
// pair left out can touch while twice the sum over steps of the largest move is under the
// margin. The few fast particles of a settled bed (its rattlers: the fastest moves 10x the
// 99th percentile) would set that pace alone: they are *hot*, every pair of theirs is near, and
// their moves do not count. A pair left out is apart throughout, its spring zero and its outputs
// zero, so the sums (each particle's own row, then its j sides in pair order) add the same numbers
// in the same order: the forces are those of the whole list, bit for bit.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "contactlab/dem/pair_list.hpp"

namespace contactlab::dem {

struct NearPairs {
  // The near pairs in the neighbour list's order (oriented and grouped by i as it is), with
  // their springs, constants and rows (j sides: PairList::index_j_sides) and the periodic shifts.
  PairList list;
  double margin = 0.0;  // m: the pairs taken had a gap under it
  // m: since the build, the sum over steps of the largest move of a particle not hot
  double moved = 0.0;
  std::uint64_t builds = 0;
  // Bit p % 8 of byte p / 8 set: particle p is hot (all its pairs taken; its moves do not count
  // in `moved`), and a zero byte past the last particle's (DriftTerms::hot reads two at once).
  std::vector<std::uint8_t> hot;
  std::size_t hot_count = 0;

  // Whether a pair left out may touch by now: twice `moved` (each particle of a pair at most
  // `moved` nearer) has reached the margin.
  bool stale() const { return 2.0 * moved >= margin; }

  // The pairs of `all` whose gap is under `margin` [m] or with a particle faster than
  // `hot_speed` [m/s] (infinity: none), from the positions, radii and velocities of the blocks
  // `kin` (particle p's x, y, z, r, vx, vy, vz at kin[stride p ..]: what the force pass reads),
  // with m* and 1/k_t as `all` has them, on `threads` threads (the same list for any count). `all`
  // must be oriented and grouped (build_csr) with its constants set. The springs come from
  // `all` where `springs_in_all` (it was just built or restored), else from this list, which
  // must have been built from the same `all` (a pair it left out has a zero spring).
  void build(const PairList& all, bool springs_in_all, const double* kin, std::size_t stride,
             std::size_t particles, double margin, double hot_speed, int threads);
  // Every spring of `all` as of now: the near pairs', and zero for the pairs left out.
  void write_back(PairList& all, int threads) const;

 private:
  // Per 64 pairs of `all`, a bit for each one taken, and the pairs taken before the word: the
  // near list's index of pair k, without a map of the neighbour list's length.
  std::vector<std::uint64_t> taken_;
  std::vector<std::uint32_t> taken_before_;
  // The next build's list and bits, swapped with these (it reads the springs of these).
  PairList next_;
  std::vector<std::uint64_t> next_taken_;
  std::vector<std::uint32_t> next_taken_before_;
};

}  // namespace contactlab::dem
