#include "contactlab/kernels/scene_io.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <sstream>

#include "contactlab/kernels/atomic_file.hpp"
#include "contactlab/kernels/error.hpp"

namespace contactlab {
namespace {

constexpr char kMagic[8] = {'C', 'L', 'S', 'C', 'E', 'N', 'E', '1'};
constexpr std::uint32_t kBinaryVersion = 1;
constexpr std::uint64_t kBinaryHeaderBytes = 8 + 4 + 4 + 8 + 48;

std::ifstream open_input(const std::string& path, std::ios::openmode mode) {
  std::ifstream in(path, mode);
  if (!in) throw InputError(path + ": cannot open file: " + std::strerror(errno));
  return in;
}

// Splits a row on commas when it has any (fields trimmed, empty ones kept so they are
// reported), else on whitespace.
std::vector<std::string> split_fields(const std::string& line) {
  std::vector<std::string> fields;
  const bool commas = line.find(',') != std::string::npos;
  std::istringstream in(line);
  std::string field;
  while (commas ? static_cast<bool>(std::getline(in, field, ','))
                : static_cast<bool>(in >> field)) {
    const std::size_t b = field.find_first_not_of(" \t\r");
    const std::size_t e = field.find_last_not_of(" \t\r");
    fields.push_back(b == std::string::npos ? std::string() : field.substr(b, e - b + 1));
  }
  if (commas && !line.empty() && line.back() == ',') fields.emplace_back();
  return fields;
}

bool parse_number(const std::string& field, double& value) {
  if (field.empty()) return false;
  char* end = nullptr;
  value = std::strtod(field.c_str(), &end);
  return end == field.c_str() + field.size();
}

}  // namespace

Scene read_text_scene(const std::string& path, const Box& box) {
  std::ifstream in = open_input(path, std::ios::in);
  Scene scene;
  scene.box = box;
  std::string line;
  std::size_t line_number = 0;
  std::size_t columns = 0;
  bool seen_row = false;
  while (std::getline(in, line)) {
    ++line_number;
    const std::size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    const std::vector<std::string> fields = split_fields(line);
    const std::string where = path + ":" + std::to_string(line_number) + ": ";
    std::array<double, 4> v{};
    bool numeric = fields.size() >= 3 && fields.size() <= 4;
    for (std::size_t k = 0; numeric && k < fields.size(); ++k)
      numeric = parse_number(fields[k], v[k]);
    if (!numeric) {
      bool all_names = !seen_row && columns == 0 && (fields.size() == 3 || fields.size() == 4);
      for (const auto& f : fields) {
        double ignored;
        if (f.empty() || parse_number(f, ignored)) all_names = false;
      }
      if (all_names) {  // the optional header row
        columns = fields.size();
        continue;
      }
      throw InputError(where + "expected 3 or 4 numbers 'x,y,z[,d]', got '" + line + "'");
    }
    if (columns == 0) columns = fields.size();
    if (fields.size() != columns) {
      throw InputError(where + "expected " + std::to_string(columns) + " columns, got " +
                       std::to_string(fields.size()));
    }
    seen_row = true;
    for (std::size_t k = 0; k < fields.size(); ++k) {
      if (!std::isfinite(v[k]))
        throw InputError(where + "NaN or infinite value '" + fields[k] + "'");
    }
    if (!box.contains(v[0], v[1], v[2])) {
      throw InputError(where + "particle (" + fields[0] + ", " + fields[1] + ", " + fields[2] +
                       ") is outside the box");
    }
    scene.x.push_back(v[0]);
    scene.y.push_back(v[1]);
    scene.z.push_back(v[2]);
    if (columns == 4) {
      if (!(v[3] > 0.0)) throw InputError(where + "diameter must be > 0, got '" + fields[3] + "'");
      scene.diameter.push_back(v[3]);
    }
  }
  if (in.bad()) throw InputError(path + ": read error");
  validate_scene(scene, path);
  return scene;
}

BinarySceneHeader read_binary_header(const std::string& path) {
  std::ifstream in = open_input(path, std::ios::binary);
  char magic[8];
  std::uint32_t version = 0, flags = 0;
  std::uint64_t n = 0;
  std::array<double, 6> bounds{};
  in.read(magic, 8);
  in.read(reinterpret_cast<char*>(&version), 4);
  in.read(reinterpret_cast<char*>(&flags), 4);
  in.read(reinterpret_cast<char*>(&n), 8);
  in.read(reinterpret_cast<char*>(bounds.data()), 48);
  if (!in || std::memcmp(magic, kMagic, 8) != 0) {
    throw InputError(path + ": not a contactlab binary scene (bad header)");
  }
  if (version != kBinaryVersion) {
    throw InputError(path + ": binary scene version " + std::to_string(version) +
                     " is not supported (expected 1)");
  }
  if (flags > 1) throw InputError(path + ": unknown flags in binary scene header");
  in.seekg(0, std::ios::end);
  const std::uint64_t size = static_cast<std::uint64_t>(in.tellg());
  const std::uint64_t arrays = flags & 1 ? 4 : 3;
  if (n > (size - kBinaryHeaderBytes) / 8 || size != kBinaryHeaderBytes + arrays * 8 * n) {
    throw InputError(path + ": file size " + std::to_string(size) + " does not match N = " +
                     std::to_string(n) + " in its header (truncated or corrupt)");
  }
  BinarySceneHeader header;
  header.n = n;
  header.diameters = (flags & 1) != 0;
  header.box = Box{{bounds[0], bounds[1], bounds[2]}, {bounds[3], bounds[4], bounds[5]}};
  return header;
}

Scene read_binary_rows(const std::string& path, const BinarySceneHeader& header,
                       std::uint64_t first, std::uint64_t last) {
  last = std::min(last, header.n);
  first = std::min(first, last);
  const std::uint64_t count = last - first;
  std::ifstream in = open_input(path, std::ios::binary);
  Scene scene;
  scene.box = header.box;
  const int arrays = header.diameters ? 4 : 3;
  for (int a = 0; a < arrays; ++a) {
    std::vector<double>& array = a == 0   ? scene.x
                                 : a == 1 ? scene.y
                                 : a == 2 ? scene.z
                                          : scene.diameter;
    array.resize(count);
    in.seekg(static_cast<std::streamoff>(kBinaryHeaderBytes + 8 * (a * header.n + first)));
    in.read(reinterpret_cast<char*>(array.data()), static_cast<std::streamsize>(8 * count));
  }
  if (!in) throw InputError(path + ": read error");
  validate_scene(scene, path, first);
  return scene;
}

Scene read_binary_scene(const std::string& path) {
  const BinarySceneHeader header = read_binary_header(path);
  return read_binary_rows(path, header, 0, header.n);
}

bool is_binary_scene(const std::string& path) {
  char magic[8] = {};
  std::ifstream in = open_input(path, std::ios::binary);
  in.read(magic, 8);
  return std::memcmp(magic, kMagic, 8) == 0;
}

Scene read_scene(const std::string& path, const Box& box) {
  if (is_binary_scene(path)) return read_binary_scene(path);
  return read_text_scene(path, box);
}

void write_binary_scene(const Scene& scene, const std::string& path) {
  write_file_atomically(
      path,
      [&](std::ostream& out) {
        const std::uint32_t version = kBinaryVersion;
        const std::uint32_t flags = scene.has_diameters() ? 1 : 0;
        const std::uint64_t n = scene.size();
        const std::array<double, 6> bounds{scene.box.lo[0], scene.box.lo[1], scene.box.lo[2],
                                           scene.box.hi[0], scene.box.hi[1], scene.box.hi[2]};
        out.write(kMagic, 8);
        out.write(reinterpret_cast<const char*>(&version), 4);
        out.write(reinterpret_cast<const char*>(&flags), 4);
        out.write(reinterpret_cast<const char*>(&n), 8);
        out.write(reinterpret_cast<const char*>(bounds.data()), 48);
        for (const auto* array : {&scene.x, &scene.y, &scene.z}) {
          out.write(reinterpret_cast<const char*>(array->data()),
                    static_cast<std::streamsize>(8 * n));
        }
        if (flags) {
          out.write(reinterpret_cast<const char*>(scene.diameter.data()),
                    static_cast<std::streamsize>(8 * n));
        }
      },
      true);
}

void write_text_scene(const Scene& scene, const std::string& path) {
  write_file_atomically(path, [&](std::ostream& out) {
    out.precision(17);
    out << (scene.has_diameters() ? "x,y,z,d\n" : "x,y,z\n");
    for (std::size_t i = 0; i < scene.size(); ++i) {
      out << scene.x[i] << ',' << scene.y[i] << ',' << scene.z[i];
      if (scene.has_diameters()) out << ',' << scene.diameter[i];
      out << '\n';
    }
  });
}

}  // namespace contactlab
