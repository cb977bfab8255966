// A particle's whole state as bytes (every array of Particles::for_each_array, in its order):
// what a migrating particle or a new ghost carries to another rank.
#pragma once

#include <cstddef>
#include <vector>

#include "contactlab/dem/particles.hpp"

namespace contactlab::dem::mpi {

// The bytes of one particle's record (the same for every particle of a run: it depends on the
// wall count only).
std::size_t record_bytes(const Particles& particles);
// Appends particle k's record to `out`.
void append_record(const Particles& particles, std::size_t k, std::vector<char>& out);
// Appends the particle of the record at `in` to `particles`; returns the bytes read.
std::size_t read_record(const char* in, Particles& particles);
// Keeps the particles whose `keep` is non-zero, in order (every array compacted).
void keep_particles(Particles& particles, const std::vector<std::uint8_t>& keep);

}  // namespace contactlab::dem::mpi
