// Deterministic scene generators: the same (kind, N, D, seed, parameters) gives bit-identical
// particles on any machine, compiler and standard library (only +, -, *, / and sqrt are used,
// all correctly rounded by IEEE 754, and FMA contraction is off).
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "contactlab/kernels/scene.hpp"

namespace contactlab {

// core: per axis 0.5 + 0.5 sign(u) |u|^3 of the box (u uniform in [-1, 1]), an extreme centre.
enum class SceneKind { kUniform, kClustered, kBlobs, kPolydisperse, kCore };

std::string_view to_string(SceneKind kind);
SceneKind parse_scene_kind(std::string_view text);  // throws InputError
std::vector<SceneKind> all_scene_kinds();

struct SceneSpec {
  SceneKind kind = SceneKind::kClustered;
  std::uint64_t n = 100'000;
  // Diameter D; for polydisperse scenes the largest diameter, the smallest being
  // D / size_ratio, drawn uniformly in between.
  double diameter = 1.0 / 200.0;
  std::uint64_t seed = 1;
  Box box;

  // Radial law of a cluster (docs/scenes.md): with s = r / R in [0, 1) the radial CDF is
  // F(s) = (s (1 + c) / (s + c))^2, so the number density is
  // n(s) ∝ 1 / (s (s + c)^3): it rises as 1/s into the centre and falls as s^-4 outside a
  // core of relative radius c. Smaller c = a sharper, denser core.
  double core = 0.3;
  double background = 0.0;    // fraction of particles spread uniformly over the box instead
  int blob_count = 8;         // blobs only
  double blob_radius = 0.15;  // blobs only: R as a fraction of the smallest box extent
  double size_ratio = 3.0;    // polydisperse only: largest / smallest diameter
};

// Throws InputError for N too large for 32-bit particle ids, D <= 0 or non-finite, or
// parameters outside their ranges.
void validate_scene_spec(const SceneSpec& spec);

Scene generate_scene(const SceneSpec& spec);

}  // namespace contactlab
