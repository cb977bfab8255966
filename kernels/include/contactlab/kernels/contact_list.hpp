// Per-particle contact counts and partner ids (the two things the paper updates), stored as
// compressed sparse rows: partners of particle i are partners[offsets[i] .. offsets[i + 1]).
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "contactlab/kernels/large_vector.hpp"

namespace contactlab {

// LargeVectors: the partners of a paper-scene run are 110 MB, and resize() does not zero them
// on one thread first (the threads that fill the rows first-touch their pages).
struct ContactList {
  LargeVector<std::uint64_t> offsets{0};  // particle_count() + 1 entries
  LargeVector<std::uint32_t> partners;

  std::size_t particle_count() const { return offsets.size() - 1; }
  std::uint32_t count(std::size_t i) const {
    return static_cast<std::uint32_t>(offsets[i + 1] - offsets[i]);
  }
  std::span<const std::uint32_t> partners_of(std::size_t i) const {
    return {partners.data() + offsets[i], partners.data() + offsets[i + 1]};
  }
  // Each contact appears in both partners' rows.
  std::uint64_t pair_count() const { return partners.size() / 2; }

  friend bool operator==(const ContactList&, const ContactList&) = default;
};

// Renames working ids to input ids (working_to_input empty = identity), moves every row to
// its input particle and sorts each row ascending: the form compared between variants. On
// `threads` threads (0: OpenMP's default team), so that a run told to use one thread uses one:
// a team of the default size left its idle worker spinning on the other core after every
// one-thread DEM rebuild.
ContactList canonicalize(const ContactList& working,
                         std::span<const std::uint32_t> working_to_input, int threads = 0);

// CSV `i,j` per contact with i < j, 0-based input rows, ascending; `canonical` must come from
// canonicalize(). Written atomically.
void write_pairs_csv(const ContactList& canonical, const std::string& path);

}  // namespace contactlab
