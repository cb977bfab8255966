// Copies of a periodic column laid under a silo and cut to it (tile.hpp).
#include "contactlab/dem/tile.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "contactlab/kernels/error.hpp"

namespace contactlab::dem {
namespace {

const LatticeSpec& cylinder_lattice(const DemConfig& target) {
  for (const LatticeSpec& s : target.lattices) {
    if (s.in_cylinder) return s;
  }
  throw InputError("dem tile: the target config '" + target.name +
                   "' has no lattice inside a cylinder to cut the copies to");
}

std::uint16_t material_in(const DemConfig& from, std::uint16_t m, const DemConfig& to) {
  const std::string& name = from.materials.at(m).name;
  for (std::size_t k = 0; k < to.materials.size(); ++k) {
    if (to.materials[k].name == name) return static_cast<std::uint16_t>(k);
  }
  throw InputError("dem tile: the target config '" + to.name + "' has no material '" + name + "'");
}

}  // namespace

TiledBed tile_column(const DemConfig& column, const CheckpointParts& column_state,
                     const DemConfig& target, std::array<int, 2> copies) {
  const Domain& box = column.settings.domain;
  if (!box.periodic[0] || !box.periodic[1] || box.periodic[2]) {
    throw InputError("dem tile: the column config '" + column.name +
                     "' must be periodic along x and y and not along z");
  }
  if (copies[0] < 1 || copies[1] < 1) throw InputError("dem tile: copies must be >= 1 per axis");
  // The copies' list is written without periodic images: a target that wraps would need them.
  const Domain& into = target.settings.domain;
  if (into.periodic[0] || into.periodic[1] || into.periodic[2]) {
    throw InputError("dem tile: the target config '" + target.name + "' is periodic");
  }
  const LatticeSpec& silo = cylinder_lattice(target);
  const double length[2] = {box.hi[0] - box.lo[0], box.hi[1] - box.lo[1]};
  // The copies' square, centred on the silo's axis, must cover its whole cross-section.
  for (int a = 0; a < 2; ++a) {
    if (copies[a] * length[a] < 2.0 * silo.cylinder_radius) {
      throw InputError("dem tile: " + std::to_string(copies[a]) + " copies of " +
                       std::to_string(length[a]) + " m along " + (a == 0 ? "x" : "y") +
                       " do not cover the silo's diameter " +
                       std::to_string(2.0 * silo.cylinder_radius) + " m");
    }
  }
  const double origin[2] = {silo.cylinder_point[0] - 0.5 * copies[0] * length[0] - box.lo[0],
                            silo.cylinder_point[1] - 0.5 * copies[1] * length[1] - box.lo[1]};
  const Particles& p = column_state.particles;
  const std::size_t n = p.size();
  const std::size_t tiles = static_cast<std::size_t>(copies[0]) * copies[1];
  auto offset = [&](std::size_t tile, int a) {
    const std::size_t index = a == 0 ? tile % copies[0] : tile / copies[0];
    return origin[a] + static_cast<double>(index) * length[a];
  };

  // Which (tile, particle) copies lie wholly inside the silo, the lowest first.
  struct Copy {
    double z;
    std::uint64_t tile_particle;  // tile * n + particle
  };
  std::vector<Copy> inside;
  for (std::size_t t = 0; t < tiles; ++t) {
    for (std::size_t k = 0; k < n; ++k) {
      const double dx = p.x[k] + offset(t, 0) - silo.cylinder_point[0];
      const double dy = p.y[k] + offset(t, 1) - silo.cylinder_point[1];
      if (std::hypot(dx, dy) + p.radius[k] <= silo.cylinder_radius) {
        inside.push_back({p.z[k], t * n + k});
      }
    }
  }
  // Ties by the copy's index, so the cut is the same on every machine.
  std::sort(inside.begin(), inside.end(), [](const Copy& a, const Copy& b) {
    return a.z < b.z || (a.z == b.z && a.tile_particle < b.tile_particle);
  });
  std::uint64_t target_count = target.particles.size();  // what make_particles(target) makes
  for (const LatticeSpec& l : target.lattices) target_count += l.count;
  TiledBed out;
  TileReport& report = out.report;
  report.copies = tiles;
  report.laid = tiles * n;
  report.kept = std::min<std::uint64_t>(inside.size(), target_count);
  report.over_count = inside.size() - report.kept;
  inside.resize(report.kept);

  // The kept copies in the column's order, tile by tile (the pair list's order follows), each
  // with its new index; the stable ids number them from the lowest up.
  constexpr std::uint32_t kNone = UINT32_MAX;
  std::vector<std::uint32_t> new_index(tiles * n, kNone), new_id(tiles * n, kNone);
  for (std::size_t r = 0; r < inside.size(); ++r) {
    new_id[inside[r].tile_particle] = static_cast<std::uint32_t>(r);
  }
  std::vector<std::uint64_t> kept;
  kept.reserve(inside.size());
  for (std::uint64_t c = 0; c < tiles * n; ++c) {
    if (new_id[c] == kNone) continue;
    new_index[c] = static_cast<std::uint32_t>(kept.size());
    kept.push_back(c);
  }

  // The column's particles with their wall springs on the target's walls (the column's wall w
  // becomes the target's wall of the same name, or is dropped), gathered into the kept copies.
  Particles q = p;
  q.set_wall_count(target.settings.walls.size());
  for (std::size_t w = 0; w < column.settings.walls.size(); ++w) {
    for (std::size_t v = 0; v < target.settings.walls.size(); ++v) {
      if (target.settings.walls[v].name != column.settings.walls[w].name) continue;
      for (int c = 0; c < 3; ++c) q.wall_spring[3 * v + c] = p.wall_spring[3 * w + c];
    }
  }
  std::vector<std::uint32_t> source(kept.size());
  for (std::size_t a = 0; a < kept.size(); ++a) source[a] = static_cast<std::uint32_t>(kept[a] % n);
  q.gather(source);
  // The lattice sites the column started from, by stable id, for the initial energy.
  const Particles column_start = make_particles(column);
  std::vector<std::uint32_t> start_of(column_start.size());
  for (std::uint32_t k = 0; k < column_start.size(); ++k) start_of[column_start.id[k]] = k;
  std::vector<std::uint16_t> material_to(column.materials.size());
  for (std::size_t m = 0; m < material_to.size(); ++m) {
    material_to[m] = material_in(column, static_cast<std::uint16_t>(m), target);
  }
  const Vec3& g = target.settings.gravity;
  double initial_energy = 0.0;
  for (std::size_t a = 0; a < kept.size(); ++a) {
    const std::size_t t = kept[a] / n;
    const double ox = offset(t, 0), oy = offset(t, 1);
    const std::size_t s = start_of.at(q.id[a]);  // still the column's id here
    q.id[a] = new_id[kept[a]];
    q.material[a] = material_to[q.material[a]];
    q.x[a] += ox;
    q.y[a] += oy;
    q.x0[a] += ox;
    q.y0[a] += oy;
    const double v2 = column_start.vx[s] * column_start.vx[s] +
                      column_start.vy[s] * column_start.vy[s] +
                      column_start.vz[s] * column_start.vz[s];
    initial_energy +=
        0.5 * column_start.mass[s] * v2 -
        column_start.mass[s] * (g[0] * (column_start.x[s] + ox) + g[1] * (column_start.y[s] + oy) +
                                g[2] * column_start.z[s]);
    report.top_z = std::max(report.top_z, q.z[a]);
  }

  // The list: pair (i, j) in tile t stands for i's copy in t and j's in the copy its image
  // code points to (code = (ix + 1) + 3 (iy + 1) + 9 (iz + 1): j's image is j + ix Lx, ...).
  const PairList& list = column_state.pairs;
  PairList& pairs = out.parts.pairs;
  for (std::size_t t = 0; t < tiles; ++t) {
    const int tx = static_cast<int>(t % copies[0]), ty = static_cast<int>(t / copies[0]);
    for (std::size_t k = 0; k < list.size(); ++k) {
      const int code = list.image[k];
      const int jx = tx + code % 3 - 1, jy = ty + code / 3 % 3 - 1;
      if (code / 9 != 1) throw InputError("dem tile: the column's list crosses z periodically");
      if (jx < 0 || jy < 0 || jx >= copies[0] || jy >= copies[1]) continue;
      const std::uint32_t i = new_index[t * n + list.i[k]];
      const std::uint32_t j = new_index[(std::size_t(jy) * copies[0] + jx) * n + list.j[k]];
      if (i == kNone || j == kNone) continue;
      pairs.i.push_back(i);
      pairs.j.push_back(j);
      pairs.image.push_back(13);  // no shift: the target is not periodic
      pairs.hx.push_back(list.hx[k]);
      pairs.hy.push_back(list.hy[k]);
      pairs.hz.push_back(list.hz[k]);
    }
  }
  report.pairs = pairs.i.size();

  Engine::State& s = out.parts.state;
  s = column_state.state;
  s.rebuilds = 0;
  s.large_overlaps = 0;
  s.removed_count = 0;
  s.removed_mass = 0.0;
  s.initial_energy = initial_energy;
  out.parts.frames = 0;
  out.parts.particles = std::move(q);
  return out;
}

}  // namespace contactlab::dem
