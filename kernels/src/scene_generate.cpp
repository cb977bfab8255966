#include "contactlab/kernels/scene_generate.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include "contactlab/kernels/error.hpp"
#include "contactlab/kernels/rng.hpp"

namespace contactlab {
namespace {

constexpr std::array<std::pair<SceneKind, std::string_view>, 5> kKindNames{{
    {SceneKind::kUniform, "uniform"},
    {SceneKind::kClustered, "clustered"},
    {SceneKind::kBlobs, "blobs"},
    {SceneKind::kPolydisperse, "polydisperse"},
    {SceneKind::kCore, "core"},
}};

struct Point {
  double x, y, z;
};

Point uniform_in_box(Xoshiro256& rng, const Box& box) {
  const double x = box.lo[0] + box.extent(0) * rng.uniform();
  const double y = box.lo[1] + box.extent(1) * rng.uniform();
  const double z = box.lo[2] + box.extent(2) * rng.uniform();
  return {x, y, z};
}

// The extreme core: per axis centre + half extent * sign(u) |u|^3, u uniform in [-1, 1]: the
// density grows without bound toward the centre planes (as |t|^(-2/3) per axis), far denser at
// the centre than the clustered law.
Point core_point(Xoshiro256& rng, const Box& box) {
  double p[3];
  for (int axis = 0; axis < 3; ++axis) {
    const double u = 2.0 * rng.uniform() - 1.0;
    const double half = 0.5 * box.extent(axis);
    p[axis] = (box.lo[axis] + half) + half * (u * u * u);
  }
  return {p[0], p[1], p[2]};
}

// A point of a cluster of radius R around `centre` whose radial CDF is
// F(s) = (s (1 + c) / (s + c))^2, s = r / R; inverted exactly: q = sqrt(u), s = c q / (1 + c - q).
// The direction is uniform on the sphere, by rejection from the cube (no trigonometry, whose
// last bit differs between math libraries).
Point clustered_point(Xoshiro256& rng, const Point& centre, double radius, double core) {
  const double q = std::sqrt(rng.uniform_open());
  const double s = core * q / (1.0 + core - q);
  double a, b, c, norm2;
  do {
    a = 2.0 * rng.uniform() - 1.0;
    b = 2.0 * rng.uniform() - 1.0;
    c = 2.0 * rng.uniform() - 1.0;
    norm2 = a * a + b * b + c * c;
  } while (norm2 > 1.0 || norm2 < 1e-12);
  const double scale = radius * s / std::sqrt(norm2);
  return {centre.x + scale * a, centre.y + scale * b, centre.z + scale * c};
}

void push(Scene& scene, Point p) {
  // Rounding can push a point a last bit past a face; the cluster never reaches it otherwise.
  p.x = std::clamp(p.x, scene.box.lo[0], scene.box.hi[0]);
  p.y = std::clamp(p.y, scene.box.lo[1], scene.box.hi[1]);
  p.z = std::clamp(p.z, scene.box.lo[2], scene.box.hi[2]);
  scene.x.push_back(p.x);
  scene.y.push_back(p.y);
  scene.z.push_back(p.z);
}

// Integer in [0, k) for k < 2^32, from the top 32 bits (multiply-shift).
std::uint64_t pick(Xoshiro256& rng, std::uint64_t k) { return ((rng.next() >> 32) * k) >> 32; }

}  // namespace

std::string_view to_string(SceneKind kind) {
  for (const auto& [k, name] : kKindNames) {
    if (k == kind) return name;
  }
  return "?";
}

SceneKind parse_scene_kind(std::string_view text) {
  for (const auto& [k, name] : kKindNames) {
    if (name == text) return k;
  }
  throw InputError("unknown scene kind '" + std::string(text) +
                   "' (choose uniform, clustered, blobs, polydisperse or core)");
}

std::vector<SceneKind> all_scene_kinds() {
  std::vector<SceneKind> kinds;
  kinds.reserve(kKindNames.size());
  for (const auto& entry : kKindNames) kinds.push_back(entry.first);
  return kinds;
}

void validate_scene_spec(const SceneSpec& spec) {
  if (spec.n >= UINT32_MAX) throw InputError("N must be below 2^32 - 1");
  if (!(spec.diameter > 0.0) || !std::isfinite(spec.diameter)) {
    throw InputError("diameter D must be a positive finite number");
  }
  if (!(spec.core > 0.0 && spec.core <= 100.0)) throw InputError("core must be in (0, 100]");
  if (!(spec.background >= 0.0 && spec.background <= 1.0)) {
    throw InputError("background must be in [0, 1]");
  }
  if (spec.blob_count < 1) throw InputError("blob count must be >= 1");
  if (!(spec.blob_radius > 0.0 && spec.blob_radius <= 0.5)) {
    throw InputError("blob radius must be in (0, 0.5]");
  }
  if (!(spec.size_ratio >= 1.0) || !std::isfinite(spec.size_ratio)) {
    throw InputError("size ratio must be >= 1");
  }
  for (int axis = 0; axis < 3; ++axis) {
    if (!(spec.box.extent(axis) > 0.0)) throw InputError("the box must have positive extent");
  }
}

Scene generate_scene(const SceneSpec& spec) {
  validate_scene_spec(spec);
  Scene scene;
  scene.box = spec.box;
  scene.reserve(spec.n);
  Xoshiro256 rng(spec.seed);
  const Box& box = spec.box;
  const double smallest = std::min({box.extent(0), box.extent(1), box.extent(2)});
  const Point centre{0.5 * (box.lo[0] + box.hi[0]), 0.5 * (box.lo[1] + box.hi[1]),
                     0.5 * (box.lo[2] + box.hi[2])};

  std::vector<Point> blob_centres;
  const double blob_radius = spec.blob_radius * smallest;
  if (spec.kind == SceneKind::kBlobs) {
    const Box inner{{box.lo[0] + blob_radius, box.lo[1] + blob_radius, box.lo[2] + blob_radius},
                    {box.hi[0] - blob_radius, box.hi[1] - blob_radius, box.hi[2] - blob_radius}};
    for (int b = 0; b < spec.blob_count; ++b) blob_centres.push_back(uniform_in_box(rng, inner));
  }

  for (std::uint64_t i = 0; i < spec.n; ++i) {
    switch (spec.kind) {
      case SceneKind::kUniform:
      case SceneKind::kPolydisperse:
        push(scene, uniform_in_box(rng, box));
        break;
      case SceneKind::kCore:
        push(scene, core_point(rng, box));
        break;
      case SceneKind::kClustered:
      case SceneKind::kBlobs:
        if (spec.background > 0.0 && rng.uniform() < spec.background) {
          push(scene, uniform_in_box(rng, box));
        } else if (spec.kind == SceneKind::kClustered) {
          push(scene, clustered_point(rng, centre, 0.5 * smallest, spec.core));
        } else {
          const Point& c = blob_centres[pick(rng, blob_centres.size())];
          push(scene, clustered_point(rng, c, blob_radius, spec.core));
        }
        break;
    }
  }
  if (spec.kind == SceneKind::kPolydisperse) {
    const double smallest_d = spec.diameter / spec.size_ratio;
    scene.diameter.resize(spec.n);
    for (auto& d : scene.diameter) d = smallest_d + (spec.diameter - smallest_d) * rng.uniform();
  }
  return scene;
}

}  // namespace contactlab
