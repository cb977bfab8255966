// Binary checkpoints: a magic word, counts, the engine's State, then raw arrays.
#include "contactlab/dem/checkpoint.hpp"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <istream>
#include <ostream>
#include <vector>

#include "contactlab/kernels/atomic_file.hpp"
#include "contactlab/kernels/error.hpp"

namespace contactlab::dem {
namespace {

// Format 2 added the sink's counters; particles may be fewer than the config's (removed).
// Format 3 dropped the six arrays of synchronised velocities (the engine predicts them from
// v and f at the next step; formats 1 and 2 still carry them, read and dropped).
constexpr char kMagic[8] = {'C', 'L', 'D', 'E', 'M', 'C', 'K', '4'};

template <class T>
void put(std::ostream& out, const T& v) {
  out.write(reinterpret_cast<const char*>(&v), sizeof(T));
}
template <class T, class Allocator>
void put_array(std::ostream& out, const std::vector<T, Allocator>& v) {
  put<std::uint64_t>(out, v.size());
  out.write(reinterpret_cast<const char*>(v.data()),
            static_cast<std::streamsize>(v.size() * sizeof(T)));
}

class Reader {
 public:
  Reader(std::istream& in, std::string path) : in_(in), path_(std::move(path)) {}
  template <class T>
  T get() {
    T v{};
    in_.read(reinterpret_cast<char*>(&v), sizeof(T));
    if (!in_) throw InputError(path_ + ": checkpoint is truncated");
    return v;
  }
  template <class T, class Allocator>
  void array(std::vector<T, Allocator>& v, std::uint64_t expected) {
    const auto n = get<std::uint64_t>();
    if (n != expected) throw InputError(path_ + ": checkpoint arrays do not match the config");
    v.resize(n);
    in_.read(reinterpret_cast<char*>(v.data()), static_cast<std::streamsize>(n * sizeof(T)));
    if (!in_) throw InputError(path_ + ": checkpoint is truncated");
  }

 private:
  std::istream& in_;
  std::string path_;
};

}  // namespace

void write_checkpoint(const Engine& engine, int frames, const std::string& path) {
  write_checkpoint(engine.state(), engine.particles(), engine.pairs(), frames, path);
}

void write_checkpoint(const Engine::State& state, const Particles& particles, const PairList& pairs,
                      int frames, const std::string& path) {
  const Engine::State& s = state;
  const Particles& p = particles;
  const PairList& q = pairs;
  write_file_atomically(
      path,
      [&](std::ostream& out) {
        out.write(kMagic, sizeof kMagic);
        put<std::uint64_t>(out, p.size());
        put<std::uint64_t>(out, p.wall_spring.size());
        put<std::uint64_t>(out, q.size());
        put<std::int32_t>(out, frames);
        put(out, s.time_s);
        put(out, s.step);
        put(out, s.rebuilds);
        put(out, s.large_overlaps);
        put(out, s.initial_energy);
        put(out, s.removed_count);
        put(out, s.removed_mass);
        put(out, s.base_time_s);
        put(out, s.base_step);
        p.for_each_array([&](const auto& v) { put_array(out, v); });
        put_array(out, q.i);
        put_array(out, q.j);
        put_array(out, q.image);
        put_array(out, q.hx);
        put_array(out, q.hy);
        put_array(out, q.hz);
      },
      true);
}

CheckpointParts read_checkpoint_parts(const std::string& path, const Particles& config) {
  std::ifstream file(path, std::ios::binary);
  if (!file) throw InputError("cannot open checkpoint '" + path + "'");
  char magic[8];
  file.read(magic, sizeof magic);
  // Formats 1 (before the sink: no sink counters), 2 and 3 are read too.
  const char version = file && std::memcmp(magic, kMagic, 7) == 0 ? magic[7] : '\0';
  if (version < '1' || version > kMagic[7]) {
    throw InputError(path + ": not a contactlab DEM checkpoint");
  }
  const bool version1 = version == '1';
  Reader in(file, path);
  const auto n = in.get<std::uint64_t>();
  const auto walls3 = in.get<std::uint64_t>();
  const auto pairs = in.get<std::uint64_t>();
  // The sink may have removed particles: a checkpoint holds at most the config's.
  if (n > config.size() || walls3 != config.wall_spring.size()) {
    throw InputError(path + ": checkpoint has " + std::to_string(n) + " particles and " +
                     std::to_string(walls3 / 3) + " walls, the config " +
                     std::to_string(config.size()) + " and " +
                     std::to_string(config.wall_spring.size() / 3));
  }
  const int frames = in.get<std::int32_t>();
  Engine::State s;
  s.time_s = in.get<double>();
  s.step = in.get<std::uint64_t>();
  s.rebuilds = in.get<std::uint64_t>();
  s.large_overlaps = in.get<std::uint64_t>();
  s.initial_energy = in.get<double>();
  if (!version1) {
    s.removed_count = in.get<std::uint64_t>();
    s.removed_mass = in.get<double>();
  }
  // Format 4 adds the time base; before it, the time restarts from the checkpoint's.
  s.base_time_s = version >= '4' ? in.get<double>() : s.time_s;
  s.base_step = version >= '4' ? in.get<std::uint64_t>() : s.step;
  Particles p = config;
  p.for_each_array([&](auto& v) {
    in.array(v, n);
    if (version < '3' && static_cast<const void*>(&v) == &p.wz) {  // then pvx .. pwz, unused
      std::vector<double> synchronised_velocity;
      for (int k = 0; k < 6; ++k) in.array(synchronised_velocity, n);
    }
  });
  std::uint32_t capacity = 0;
  for (const std::uint32_t id : config.id) capacity = std::max(capacity, id + 1);
  std::vector<std::uint8_t> seen(capacity, 0);
  for (std::uint32_t id : p.id) {
    if (id >= seen.size() || seen[id] != 0) {
      throw InputError(path + ": checkpoint particle ids do not match the config");
    }
    seen[id] = 1;
  }
  PairList q;
  in.array(q.i, pairs);
  in.array(q.j, pairs);
  in.array(q.image, pairs);
  in.array(q.hx, pairs);
  in.array(q.hy, pairs);
  in.array(q.hz, pairs);
  for (std::size_t k = 0; k < pairs; ++k) {
    if (q.i[k] >= n || q.j[k] >= n || q.image[k] >= 27) {
      throw InputError(path + ": checkpoint pair list is corrupt");
    }
  }
  return {frames, s, std::move(p), std::move(q)};
}

int read_checkpoint(Engine& engine, const std::string& path) {
  CheckpointParts parts = read_checkpoint_parts(path, engine.particles());
  engine.restore(parts.state, std::move(parts.particles), std::move(parts.pairs));
  return parts.frames;
}

}  // namespace contactlab::dem
