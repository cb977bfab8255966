#include "contactlab/kernels/brute_force.hpp"

#include "contactlab/kernels/pair_test.hpp"

namespace contactlab {

ContactList brute_force_contacts(const Scene& scene, double diameter) {
  const std::size_t n = scene.size();
  const double reach_sq = diameter * diameter;
  std::vector<std::vector<std::uint32_t>> rows(n);
#pragma omp parallel for schedule(dynamic, 64)
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = 0; j < n; ++j) {
      if (i == j) continue;
      const double dx = scene.x[i] - scene.x[j];
      const double dy = scene.y[i] - scene.y[j];
      const double dz = scene.z[i] - scene.z[j];
      const bool touching = scene.has_diameters()
                                ? in_contact(dx, dy, dz, scene.diameter[i], scene.diameter[j])
                                : in_contact(dx, dy, dz, reach_sq);
      if (touching) rows[i].push_back(static_cast<std::uint32_t>(j));
    }
  }
  ContactList list;
  list.offsets.assign(n + 1, 0);
  for (std::size_t i = 0; i < n; ++i) list.offsets[i + 1] = list.offsets[i] + rows[i].size();
  list.partners.reserve(list.offsets[n]);
  for (const auto& row : rows) list.partners.insert(list.partners.end(), row.begin(), row.end());
  return list;
}

}  // namespace contactlab
