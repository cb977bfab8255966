// Reading and writing particle files.
//
// Text: one particle a row, `x,y,z` or `x,y,z,d`, separated by commas or whitespace; an optional
// header row of names; blank lines and lines starting with '#' are skipped.
//
// Binary (docs/file-formats.md), little-endian:
//   bytes 0-7   magic "CLSCENE1"
//   uint32      format version (1)
//   uint32      flags: bit 0 set when per-particle diameters follow
//   uint64      N
//   double[6]   box xmin, ymin, zmin, xmax, ymax, zmax
//   double[N]   x, then double[N] y, double[N] z, then double[N] d when flagged
#pragma once

#include <cstdint>
#include <string>

#include "contactlab/kernels/scene.hpp"

namespace contactlab {

// Reads a text or binary scene (chosen by the file's first bytes), validated against `box`
// for text files (binary files carry their own box). Throws InputError naming the file and,
// for text, the line.
Scene read_scene(const std::string& path, const Box& box);

Scene read_text_scene(const std::string& path, const Box& box);
Scene read_binary_scene(const std::string& path);
bool is_binary_scene(const std::string& path);  // the file starts with the binary magic

// A binary scene read in parts (each MPI process its share): the header, checked against the
// file size, then the rows [first, last) (clamped to N), validated with their file row numbers.
struct BinarySceneHeader {
  std::uint64_t n = 0;
  bool diameters = false;
  Box box;
};
BinarySceneHeader read_binary_header(const std::string& path);
Scene read_binary_rows(const std::string& path, const BinarySceneHeader& header,
                       std::uint64_t first, std::uint64_t last);

// Write through a temporary file renamed into place: an existing file survives a failure.
void write_binary_scene(const Scene& scene, const std::string& path);
void write_text_scene(const Scene& scene, const std::string& path);

}  // namespace contactlab
