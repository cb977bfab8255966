// O(N^2) reference contact detection: the ground truth every variant is tested against.
#pragma once

#include "contactlab/kernels/contact_list.hpp"
#include "contactlab/kernels/scene.hpp"

namespace contactlab {

// Canonical contacts (input ids, rows ascending). Uses per-particle diameters when the scene
// has them, else `diameter` for all.
ContactList brute_force_contacts(const Scene& scene, double diameter);

}  // namespace contactlab
