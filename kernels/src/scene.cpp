#include "contactlab/kernels/scene.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <sstream>

#include "contactlab/kernels/error.hpp"

namespace contactlab {

Box parse_box(const std::string& text) {
  std::array<double, 6> v{};
  std::size_t pos = 0;
  for (int k = 0; k < 6; ++k) {
    const std::size_t comma = text.find(',', pos);
    const std::string part = text.substr(pos, comma == std::string::npos ? comma : comma - pos);
    char* end = nullptr;
    v[k] = std::strtod(part.c_str(), &end);
    if (part.empty() || end == part.c_str() || *end != '\0' || !std::isfinite(v[k])) {
      throw InputError("--box expects xmin,ymin,zmin,xmax,ymax,zmax as finite numbers, got '" +
                       text + "'");
    }
    if ((comma == std::string::npos) != (k == 5)) {
      throw InputError("--box expects exactly 6 comma-separated numbers, got '" + text + "'");
    }
    pos = comma + 1;
  }
  Box box{{v[0], v[1], v[2]}, {v[3], v[4], v[5]}};
  for (int axis = 0; axis < 3; ++axis) {
    if (!(box.hi[axis] > box.lo[axis])) {
      throw InputError("--box: max must exceed min on every axis, got '" + text + "'");
    }
  }
  return box;
}

void Scene::reserve(std::size_t n) {
  x.reserve(n);
  y.reserve(n);
  z.reserve(n);
}

double Scene::max_diameter() const {
  return diameter.empty() ? 0.0 : *std::max_element(diameter.begin(), diameter.end());
}

void validate_scene(const Scene& scene, const std::string& source, std::size_t first_row) {
  for (int axis = 0; axis < 3; ++axis) {
    if (!std::isfinite(scene.box.lo[axis]) || !std::isfinite(scene.box.hi[axis]) ||
        !(scene.box.hi[axis] > scene.box.lo[axis])) {
      throw InputError(source + ": the box must have finite bounds with max > min on every axis");
    }
  }
  if (scene.y.size() != scene.x.size() || scene.z.size() != scene.x.size() ||
      (!scene.diameter.empty() && scene.diameter.size() != scene.x.size())) {
    throw InputError(source + ": coordinate arrays differ in length");
  }
  for (std::size_t i = 0; i < scene.size(); ++i) {
    const double x = scene.x[i], y = scene.y[i], z = scene.z[i];
    if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z)) {
      throw InputError(source + ": particle " + std::to_string(first_row + i) +
                       " has a NaN or infinite coordinate");
    }
    if (!scene.box.contains(x, y, z)) {
      std::ostringstream out;
      out.precision(17);
      out << source << ": particle " << first_row + i << " at (" << x << ", " << y << ", " << z
          << ") is outside the box";
      throw InputError(out.str());
    }
    if (!scene.diameter.empty() && !(scene.diameter[i] > 0.0 && std::isfinite(scene.diameter[i]))) {
      throw InputError(source + ": particle " + std::to_string(first_row + i) +
                       " has a diameter that is not a positive finite number");
    }
  }
}

namespace {
void fnv1a(std::uint64_t& hash, const std::vector<double>& values) {
  for (const double v : values) {
    std::uint64_t bits;
    std::memcpy(&bits, &v, sizeof bits);
    for (int byte = 0; byte < 8; ++byte) {
      hash ^= (bits >> (8 * byte)) & 0xffu;
      hash *= 0x100000001b3ULL;
    }
  }
}
}  // namespace

std::uint64_t scene_checksum(const Scene& scene) {
  std::uint64_t hash = 0xcbf29ce484222325ULL;
  fnv1a(hash, {scene.box.lo[0], scene.box.lo[1], scene.box.lo[2], scene.box.hi[0], scene.box.hi[1],
               scene.box.hi[2]});
  fnv1a(hash, scene.x);
  fnv1a(hash, scene.y);
  fnv1a(hash, scene.z);
  fnv1a(hash, scene.diameter);
  return hash;
}

}  // namespace contactlab
