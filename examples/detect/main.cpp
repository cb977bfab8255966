// Uses the installed contactlab::kernels: generates a clustered scene, finds its contacts with
// the paper's best variant and checks them against the O(N^2) brute force.
#include <cstdio>

#include "contactlab/kernels/brute_force.hpp"
#include "contactlab/kernels/detector.hpp"
#include "contactlab/kernels/scene_generate.hpp"

int main() {
  contactlab::SceneSpec spec;
  spec.kind = contactlab::SceneKind::kClustered;
  spec.n = 5000;
  spec.diameter = 0.02;
  const contactlab::Scene scene = contactlab::generate_scene(spec);
  contactlab::ContactDetector detector;
  const contactlab::DetectRun run = detector.run(
      scene, {contactlab::parse_variant("particle/sorted/static,200"), spec.diameter, 2, nullptr});
  const auto reference = contactlab::brute_force_contacts(scene, spec.diameter);
  const bool same = detector.canonical_contacts() == reference;
  std::printf("%zu contacts, %s the brute force\n", static_cast<std::size_t>(run.contact_pairs),
              same ? "equal to" : "DIFFERENT FROM");
  return same ? 0 : 1;
}
