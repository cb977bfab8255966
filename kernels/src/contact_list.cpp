#include "contactlab/kernels/contact_list.hpp"

#include <algorithm>

#include "contactlab/kernels/atomic_file.hpp"

namespace contactlab {

ContactList canonicalize(const ContactList& working,
                         std::span<const std::uint32_t> working_to_input) {
  const std::size_t n = working.particle_count();
  auto input_of = [&](std::size_t w) -> std::uint32_t {
    return working_to_input.empty() ? static_cast<std::uint32_t>(w) : working_to_input[w];
  };
  ContactList canonical;
  canonical.offsets.assign(n + 1, 0);
  for (std::size_t w = 0; w < n; ++w) canonical.offsets[input_of(w) + 1] = working.count(w);
  for (std::size_t i = 0; i < n; ++i) canonical.offsets[i + 1] += canonical.offsets[i];
  canonical.partners.resize(working.partners.size());
#pragma omp parallel for schedule(dynamic, 1024)
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
