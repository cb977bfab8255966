// A large settled bed from a small one: copies of a periodic column's state laid side by side
// under a silo and cut to it (as LAMMPS's `replicate`, then a cut), so a 900,000-particle
// hopper starts from a bed made in minutes instead of a fill of hours.
#pragma once

#include <array>
#include <cstdint>

#include "contactlab/dem/checkpoint.hpp"
#include "contactlab/dem/config.hpp"

namespace contactlab::dem {

struct TileReport {
  std::uint64_t copies = 0;      // copies of the column laid
  std::uint64_t laid = 0;        // particles in them
  std::uint64_t kept = 0;        // inside the silo (and among the lowest the target holds)
  std::uint64_t over_count = 0;  // inside, but above the target's particle count: left out
  std::uint64_t pairs = 0;       // pairs of the list kept (both partners kept)
  double top_z = 0.0;            // the highest kept centre [m]
};

struct TiledBed {
  CheckpointParts parts;
  TileReport report;
};

// The column's state (`column_state`, a checkpoint of `column`: periodic along x and y, not z)
// copied `copies[0]` x `copies[1]` times, the copies' square centred on the axis of the target's
// first lattice that lies inside a cylinder, and cut to that cylinder: a particle is kept when
// its whole sphere is inside (no contact with the silo's wall). Positions, velocities, forces,
// springs and the neighbour list (with each pair's partner taken from the copy its periodic
// image stood in) carry over; a wall spring goes to the target's wall of the same name. When
// more particles are inside than the target's config holds, the lowest are kept. Ids are
// 0, 1, ... from the lowest up; the time and step are the column's; the initial energy is the
// kept particles' at their lattice sites (so the dissipated energy stays what they lost).
// Throws InputError naming the problem (a column not periodic in x and y, a periodic target, a
// target without a cylinder lattice, copies that do not cover the cylinder, a material the target
// lacks).
TiledBed tile_column(const DemConfig& column, const CheckpointParts& column_state,
                     const DemConfig& target, std::array<int, 2> copies);

}  // namespace contactlab::dem
