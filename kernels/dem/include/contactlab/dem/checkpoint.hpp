// Checkpoints of a DEM run: the complete engine state (particles in their current order, the
// neighbour list with its contact history, counters) in a binary file written atomically, so
// a restarted run continues bit-identically.
#pragma once

#include <string>

#include "contactlab/dem/engine.hpp"

namespace contactlab::dem {

// `frames`: the output frames written so far (the restarted run continues the numbering).
void write_checkpoint(const Engine& engine, int frames, const std::string& path);
// The same file from its parts: an engine's state, its particles in their order and its list
// with history (what a decomposed run assembles on one rank: dem_mpi/checkpoint.hpp).
void write_checkpoint(const Engine::State& state, const Particles& particles, const PairList& pairs,
                      int frames, const std::string& path);

// Restores `engine` (built from the same config) from `path`; returns the frame count. Throws
// InputError for a missing, truncated or foreign file, or one with more particles than the
// config (fewer is fine: the sink removes some), ids the config lacks, or another wall count.
int read_checkpoint(Engine& engine, const std::string& path);

// What a checkpoint holds, checked against the config's particles (`config`, their wall springs
// sized: as read_checkpoint checks them): for a run that starts from it other than by
// Engine::restore (a decomposed run splits it over its processes).
struct CheckpointParts {
  int frames = 0;
  Engine::State state;
  Particles particles;
  PairList pairs;
};
CheckpointParts read_checkpoint_parts(const std::string& path, const Particles& config);

}  // namespace contactlab::dem
