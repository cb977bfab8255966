// The generator parameters of a scene, declared once: the CLI's scene options and the
// experiment configs' scene keys are both made from this table (docs/experiments.md).
#pragma once

#include <array>
#include <cstdint>
#include <string_view>
#include <variant>

#include "contactlab/kernels/scene_generate.hpp"

namespace contactlab {

// A number of SceneSpec and the range an experiment config accepts for it. The CLI does not
// check these ranges (generate_scene's validate_scene_spec still rejects bad values); the
// configs have always checked them early, naming the JSON path.
template <class T>
struct SceneField {
  T SceneSpec::*member;
  T low;
  T high;
};

struct SceneParameter {
  std::string_view option;  // CLI option, e.g. "--size-ratio"
  std::string_view key;     // experiment-config key, e.g. "size_ratio"
  std::string_view help;    // CLI help text
  bool required;            // a generated scene of a config must give it (else SceneSpec's default)
  std::variant<SceneField<std::uint64_t>, SceneField<int>, SceneField<double>> field;
};

// The numeric parameters, in the order configs read them. Kind, diameter and box are not
// here: each has its own handling (a named kind; a diameter that file scenes share and that
// is required; a box that only the CLI takes, as text) in the CLI and in the config reader.
inline constexpr std::array<SceneParameter, 7> kSceneParameters{{
    {"--n", "n", "number of particles of a generated scene", true,
     SceneField<std::uint64_t>{&SceneSpec::n, 0, UINT32_MAX - 1}},
    {"--seed", "seed", "generator seed", false,
     SceneField<std::uint64_t>{&SceneSpec::seed, 0, UINT64_MAX}},
    {"--core", "core", "clustered/blobs: relative core radius c (docs/scenes.md)", false,
     SceneField<double>{&SceneSpec::core, 1e-6, 100.0}},
    {"--background", "background", "clustered/blobs: fraction spread uniformly", false,
     SceneField<double>{&SceneSpec::background, 0.0, 1.0}},
    {"--blobs", "blobs", "blobs: number of clusters", false,
     SceneField<int>{&SceneSpec::blob_count, 1, 1'000'000}},
    {"--blob-radius", "blob_radius",
     "blobs: cluster radius R, a fraction of the smallest box extent", false,
     SceneField<double>{&SceneSpec::blob_radius, 1e-6, 0.5}},
    {"--size-ratio", "size_ratio", "polydisperse: largest / smallest diameter", false,
     SceneField<double>{&SceneSpec::size_ratio, 1.0, 1e6}},
}};

}  // namespace contactlab
