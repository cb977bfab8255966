#include "contactlab/kernels/contact_list.hpp"

#include <omp.h>

#include <algorithm>
#include <vector>

#include "contactlab/kernels/atomic_file.hpp"
#include "contactlab/kernels/count_then_fill.hpp"

namespace contactlab {

ContactList canonicalize(const ContactList& working,
                         std::span<const std::uint32_t> working_to_input, int threads) {
  const std::size_t n = working.particle_count();
  const int team = threads > 0 ? threads : omp_get_max_threads();
  auto input_of = [&](std::size_t w) -> std::uint32_t {
    return working_to_input.empty() ? static_cast<std::uint32_t>(w) : working_to_input[w];
  };
  // Each row's count at its input row, then their running sums: no pass of length n on one
  // thread.
  ContactList canonical;
  canonical.offsets.resize(n + 1);
#pragma omp parallel for schedule(static) num_threads(team)
  for (std::size_t i = 0; i <= n; ++i) canonical.offsets[i] = 0;
#pragma omp parallel for schedule(static) num_threads(team)
  for (std::size_t w = 0; w < n; ++w) canonical.offsets[input_of(w) + 1] = working.count(w);
  std::vector<std::uint64_t> range_sums;
  parallel_inclusive_scan(canonical.offsets.data() + 1, n, team, range_sums);
  canonical.partners.resize(working.partners.size());
#pragma omp parallel for schedule(dynamic, 1024) num_threads(team)
  for (std::size_t w = 0; w < n; ++w) {
    std::uint32_t* row = canonical.partners.data() + canonical.offsets[input_of(w)];
    std::uint32_t* out = row;
    for (const std::uint32_t j : working.partners_of(w)) *out++ = input_of(j);
    std::sort(row, out);
  }
  return canonical;
}

void write_pairs_csv(const ContactList& canonical, const std::string& path) {
  write_file_atomically(path, [&](std::ostream& out) {
    out << "i,j\n";
    std::string line;
    for (std::size_t i = 0; i < canonical.particle_count(); ++i) {
      for (const std::uint32_t j : canonical.partners_of(i)) {
        if (j <= i) continue;
        line.clear();
        line += std::to_string(i);
        line += ',';
        line += std::to_string(j);
        line += '\n';
        out << line;
      }
    }
  });
}

}  // namespace contactlab
