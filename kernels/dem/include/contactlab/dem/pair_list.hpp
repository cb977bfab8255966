// The DEM half neighbour list (pairs within r_i + r_j + skin, each once) with the contact
// history aligned to it, rebuilt from the shared cell traversal (ContactDetector::neighbor_list)
// with periodic images, particles reordered by cell (ties by stable id), history carried by a
// sorted-key merge.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <vector>

#include "contactlab/dem/particles.hpp"
#include "contactlab/kernels/detector.hpp"
#include "contactlab/kernels/large_vector.hpp"

namespace contactlab::dem {

// The simulation domain: periodic axes wrap at [lo, hi); other axes are unbounded (walls bound
// them), lo/hi there only describe the scene.
struct Domain {
  std::array<double, 3> lo{0, 0, 0}, hi{1, 1, 1};  // m
  std::array<bool, 3> periodic{false, false, false};
  double length(int axis) const { return hi[axis] - lo[axis]; }
};

// Periodic image of the partner: code = (ix + 1) + 3 (iy + 1) + 9 (iz + 1), the partner's image
// at x_j + (ix Lx, iy Ly, iz Lz). kNoImage: the partner itself.
inline constexpr std::uint8_t kNoImage = 13;

// v resized to n elements, every one of which the caller then writes: past its capacity it is
// replaced, not grown (nothing is copied), with an eighth to spare. A list that gains a few pairs
// from one rebuild to the next, or a buffer swapped with one, then keeps its storage: grown
// exactly, the pairs' arrays and their scratch were reallocated, copied and faulted in at nearly
// every rebuild (the settled bed: 7 ms of a 54 ms rebuild in the pairs' resize alone, and page
// faults do not get faster with more threads).
inline constexpr std::size_t with_spare(std::size_t n) { return n + n / 8; }
template <class T, class Allocator>
void resize_to_overwrite(std::vector<T, Allocator>& v, std::size_t n) {
  if (n > v.capacity()) {
    std::vector<T, Allocator> fresh;
    fresh.reserve(with_spare(n));
    v.swap(fresh);
  }
  v.resize(n);
}

// What a stable radix sort of indices works in (keys and payloads, and their scratch), kept
// between rebuilds so that no rebuild zeroes or faults in fresh arrays of the pairs' length (and
// the arrays it swaps with keep their grown capacity).
struct RadixBuffers {
  std::vector<std::uint64_t> keys, key_scratch;
  std::vector<std::uint32_t> payload, payload_scratch;
  // What the pairs' arrays are gathered into and swapped with (payload_scratch for the indices).
  std::vector<std::uint8_t> byte_scratch;
  AlignedVector<double> real_scratch;
};

struct PairList {
  std::vector<std::uint32_t> i, j;   // particle indices (current order)
  std::vector<std::uint8_t> image;   // periodic image code of j
  AlignedVector<double> hx, hy, hz;  // tangential spring xi [m], oriented as seen from i
  // The full list's next-step springs: its j sides recompute a pair from the springs of this
  // step while the i side writes the new ones here (swapped in after the pass; not saved).
  AlignedVector<double> hx_next, hy_next, hz_next;
  // Per pair, the law's constants that depend only on the two particles: the reduced mass
  // m* = m_i m_j / (m_i + m_j) [kg] and 1 / k_t [m/N] (0 where k_t is 0). Set by the engine
  // whenever the list is built or restored (Engine::index_pair_constants), not saved: the
  // force pass streams them instead of dividing per pair per step.
  AlignedVector<double> m_star, inv_kt;
  // Pairs run from the later particle to the earlier (j < i) and are grouped by i, ascending:
  // particle a's own pairs are [rows[a], rows[a + 1]). The pairs where a is the j:
  // j_pairs[j_offsets[a] .. j_offsets[a + 1]), in pair order; they lie in the rows
  // (a, a + max_span].
  std::vector<std::uint32_t> rows, j_offsets, j_pairs;
  std::size_t max_span = 0;
  std::array<std::array<double, 3>, 27> shift{};  // image code -> shift [m]

  std::size_t size() const { return i.size(); }
  void resize(std::size_t n);
  // As resize, for a list the caller fills anew (i, j, image, springs).
  void resize_to_overwrite(std::size_t n);
  // Orients (j < i, springs and images follow), groups by i, and indexes rows (index_rows), on
  // `threads` threads (the same lists for any count).
  void build_csr(std::size_t particles, int threads, RadixBuffers& buffers);
  void build_csr(std::size_t particles);
  // build_csr's index alone, for a list already oriented and grouped: the rows and max_span.
  // The j sides, which only the full list's force pass reads, on demand (4 ms of the settled
  // bed's 60 ms rebuild at one thread, where no pass read them), and whether they are current.
  void index_rows(std::size_t particles, int threads);
  void index_j_sides(std::size_t particles, int threads, RadixBuffers& buffers);
  bool j_sides_indexed = false;
};

// The j sides that one thread's rows of the ordered force pass give particles another thread
// owns (force_pass.hpp), appended in pair order and added by the owner once it has waited for
// this thread's rows (RowsDone): per pair its record (kRecordDoubles: the force on i [N], j gets
// minus it; n x F_t [N], j's torque is -r_j times it; 1 if touching; the overlap flag), its j
// and, with rolling resistance, the rolling torque on i [N m] (j gets minus it). Only these
// pairs are kept: a thread's range meets the next ones' in about max_span particles, whatever
// the list's size.
struct LeftJSides {
  static constexpr std::size_t kRecordDoubles = 8;
  AlignedVector<double> records;
  std::vector<std::uint32_t> j;
  std::vector<double> roll_x, roll_y, roll_z;
  std::size_t count = 0;  // the sides held (the arrays only grow, from step to step)

  // Room for one more side: grown by doubling, so appending is amortised O(1).
  void reserve_one(bool rolling) {
    if (count < j.size()) return;
    const std::size_t room = std::max<std::size_t>(64, 2 * j.size());
    records.resize(kRecordDoubles * room);
    j.resize(room);
    for (auto* v : {&roll_x, &roll_y, &roll_z}) v->resize(rolling ? room : 0);
  }
};

// Tangential springs by stable-id pair, key = lower id << 32 | higher id, each spring seen from
// the lower id: what a rebuild carries from the old list to the new one, and what a decomposed
// run sends along with the particles that change process.
struct CarriedSprings {
  std::vector<std::uint64_t> keys;
  std::vector<double> springs;  // 3 per key, in key order of insertion
  std::size_t size() const { return keys.size(); }
  void clear() {
    keys.clear();
    springs.clear();
  }
  void add(std::uint64_t key, double sx, double sy, double sz) {
    keys.push_back(key);
    springs.insert(springs.end(), {sx, sy, sz});
  }
};
std::uint64_t spring_key(std::uint32_t id_a, std::uint32_t id_b);
// The springs of the list's touching pairs (a non-zero spring), in pair order, gathered on
// `threads` threads.
void collect_springs(const Particles& particles, const PairList& pairs, CarriedSprings& out,
                     int threads = 1);

// What the processes of a decomposed run agree on during a rebuild, so that each builds its
// particles' list on the grid one process would use (the same cells, hence the same order and
// sums): the largest radius, and the box of every process's particles and periodic images.
// One process passes none.
class RankAgreement {
 public:
  virtual ~RankAgreement() = default;
  virtual double max_over_ranks(double local) = 0;
  virtual Box box_over_ranks(const Box& local) = 0;
};

struct RebuildStats {
  std::size_t pairs = 0, carried_contacts = 0, ghosts = 0;
};

class NeighborBuilder {
 public:
  // Reorders `particles` by cell (within a cell by stable id), rebuilds `pairs` for `skin` [m]
  // and carries every non-zero tangential spring (pair and wall) to the new list. Periodic
  // positions are wrapped into the domain first. The candidate search runs on `threads`
  // threads; the result is the same for any count. The order and every row depend only on the
  // particles' ids, positions and the grid: a process holding a subset of them (and the same
  // grid, through `ranks`) gets the one-process order restricted to its particles. The old
  // list's springs are looked up in its rows where it has rows for these particles (its last
  // build_csr), else merged by stable-id keys; with `carried`, its springs are carried instead
  // (the old list's indices may no longer match the particles). Throws InputError if a periodic
  // length is under 3 pair reaches.
  RebuildStats rebuild(Particles& particles, PairList& pairs, const Domain& domain, double skin,
                       int threads = 1, RankAgreement* ranks = nullptr,
                       CarriedSprings* carried = nullptr);

 private:
  ContactDetector detector_;
  Scene scene_;
  std::vector<std::uint32_t> ghost_owner_;
  std::vector<std::uint8_t> ghost_image_;
  std::vector<std::uint32_t> by_id_, row_order_, order_, new_index_;
  std::vector<std::uint64_t> pair_start_, range_sums_;  // pairs of each new particle; the scan's
  RadixBuffers sort_;  // the new list's keys and payloads, and every sort's scratch
  std::vector<std::uint32_t> old_payload_;
  CarriedSprings old_springs_;
  // The old list's rows, partners and springs while the new list is written (its arrays'
  // storage, swapped back and forth from rebuild to rebuild).
  std::vector<std::uint32_t> old_rows_, old_j_;
  AlignedVector<double> old_hx_, old_hy_, old_hz_;
};

// LSD radix sort of keys < 2^bits with their payloads (stable): O(n / P + 2048 P) per 11-bit
// digit on P = `threads` threads (each counts and scatters an equal range), the same result for
// any P.
void radix_sort(std::vector<std::uint64_t>& keys, std::vector<std::uint32_t>& payload, int bits,
                std::vector<std::uint64_t>& key_scratch,
                std::vector<std::uint32_t>& payload_scratch, int threads = 1);

}  // namespace contactlab::dem
