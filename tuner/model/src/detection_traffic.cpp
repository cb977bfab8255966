#include "contactlab/tuner_model/detection_traffic.hpp"

#include <algorithm>
#include <bit>
#include <stdexcept>

#include "contactlab/kernels/cell_grid.hpp"

namespace contactlab::tuner {

std::uint64_t candidate_fetches(const WorkView& work) {
  std::uint64_t fetches = 0;
  for (std::size_t i = 0; i < work.tests.size(); ++i) {
    const std::uint32_t homes = work.homes.empty() ? 1 : std::max<std::uint32_t>(work.homes[i], 1);
    fetches += work.tests[i] / homes;
  }
  return fetches;
}

DetectionTraffic detection_traffic(const Variant& variant, const DetectionWork& work) {
  if (work.particles == 0) throw std::invalid_argument("detection_traffic: no particles");
  if (work.cell_keys == 0) throw std::invalid_argument("detection_traffic: no cell keys");
  const auto n = static_cast<double>(work.particles);
  const auto keys = static_cast<double>(work.cell_keys);
  const auto entries = static_cast<double>(work.entries);
  const double arrays = work.diameters ? 4.0 : 3.0;
  const double input_record = 8.0 * arrays;  // the scene's doubles
  const double record = (variant.precision == Precision::kFloat ? 4.0 : 8.0) * arrays;
  const bool sorted = variant.order != Order::kUnsorted;
  // What the kernels' registration and detector decide from the scene's size (cell_grid.hpp).
  const bool copied = n * arrays * sizeof(double) >= static_cast<double>(kCopyForRandomReadsFrom);
  const double finds = variant.stencil == Stencil::kHalf ? entries / 2.0 : entries;

  DetectionTraffic t;
  // Registration: the coordinates read, a (key, particle) pair of 8 bytes written, then read and
  // written by every 8-bit radix pass; the cell index written one entry (4 bytes) a key.
  const auto key_bits = static_cast<int>(std::bit_width(work.cell_keys - 1));
  const int radix_passes = key_bits <= 8 ? 1 : (key_bits + 7) / 8;
  const auto passes = static_cast<double>(radix_passes);
  t.setup_bytes = n * (input_record + 8.0) + passes * 2.0 * 8.0 * n + 4.0 * keys;
  if (sorted) {
    // The reordering gathers each particle's coordinates in cell order (the input order is the
    // scene's, not the cells'): past copy_for_random_reads, one line of the 32-byte record that
    // the keys' pass streamed (CellRegistry::assign), else a line of each array; and writes the
    // sorted record and reads the slot -> particle map.
    const double gathered = copied ? kStagedBytes + kLineBytes : arrays * kLineBytes;
    t.setup_bytes += n * (gathered + record + 4.0);
  } else {
    // The slot maps both ways, and a copy of the coordinates in the input order: narrowed for
    // float, into huge pages for double past copy_for_random_reads
    // (ContactDetector::copy_in_input_order).
    const bool copy = variant.precision == Precision::kFloat || copied;
    t.setup_bytes += n * (8.0 + (copy ? record : 0.0));
  }
  // The loop: sorted, each particle's record streamed once (the three layers of cells a row of
  // the stencil reaches are taken to stay in cache while the sweep crosses them) and the cell
  // index read once; unsorted, a line of each array per home and per candidate fetched (the
  // homes come in the scene's order, so the next home's neighbours are elsewhere) and the
  // candidate's id from the cell list. Both write their finds (4 bytes each) to the threads'
  // buffers.
  const double lines = arrays * kLineBytes;
  t.loop_bytes = sorted
                     ? n * record + 4.0 * keys
                     : static_cast<double>(work.fetches) * (lines + 4.0) + n * lines + 4.0 * keys;
  t.loop_bytes += 4.0 * finds;
  // The assembly: the finds read back and every row written (4 bytes an entry); the row offsets
  // (8 bytes a particle) and, half stencil, each row's reverse count (4 read, 4 written).
  t.rows_bytes = 4.0 * finds + 4.0 * entries;
  t.offsets_bytes = 8.0 * n + (variant.stencil == Stencil::kHalf ? 8.0 * n : 0.0);
  // What the loop reads at will: the coordinates it tests (with the slot maps, unsorted) and the
  // cell index. Its output is written as a stream.
  t.footprint_bytes = static_cast<std::uint64_t>(n * (record + (sorted ? 0.0 : 8.0)) + 4.0 * keys);
  return t;
}

}  // namespace contactlab::tuner
