// Particle records (particle_records.hpp).
#include "particle_records.hpp"

#include <cstring>

namespace contactlab::dem::mpi {

std::size_t record_bytes(const Particles& particles) {
  std::size_t bytes = 0;
  particles.for_each_array([&](const auto& v) { bytes += sizeof(v[0]); });
  return bytes;
}

void append_record(const Particles& particles, std::size_t k, std::vector<char>& out) {
  particles.for_each_array([&](const auto& v) {
    const char* at = reinterpret_cast<const char*>(&v[k]);
    out.insert(out.end(), at, at + sizeof(v[k]));
  });
}

std::size_t read_record(const char* in, Particles& particles) {
  std::size_t at = 0;
  particles.for_each_array([&](auto& v) {
    typename std::remove_reference_t<decltype(v)>::value_type value;
    std::memcpy(&value, in + at, sizeof value);
    at += sizeof value;
    v.push_back(value);
  });
  return at;
}

void keep_particles(Particles& particles, const std::vector<std::uint8_t>& keep) {
  particles.for_each_array([&](auto& v) {
    std::size_t kept = 0;
    for (std::size_t a = 0; a < v.size(); ++a) {
      if (keep[a] != 0) v[kept++] = v[a];
    }
    v.resize(kept);
  });
}

}  // namespace contactlab::dem::mpi
