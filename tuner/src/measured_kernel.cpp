#include "contactlab/tuner/measured_kernel.hpp"

#include "contactlab/tuner/sweep.hpp"

namespace contactlab::tuner {

double KernelRun::phase_s(std::string_view name) const {
  for (const auto& [phase, seconds] : phases_s) {
    if (phase == name) return seconds;
  }
  return 0.0;
}

std::vector<double> MeasuredKernel::samples(const Variant& variant, int threads, int count) {
  std::vector<double> result;
  for (int i = 0; i < count; ++i) result.push_back(run(variant, threads).phase_s(tuned_phase()));
  return result;
}

KernelRun DetectionKernel::run(const Variant& variant, int threads) {
  const DetectRun r = detector_.run(scene_, DetectOptions{variant, diameter_, threads, nullptr});
  return {{{"setup", r.setup_s}, {"detect", r.detect_s}},
          {{"candidate_tests", r.candidate_tests}, {"contact_pairs", r.contact_pairs}}};
}

LoopWork DetectionKernel::iteration_work(const Variant& variant, int threads) {
  return detector_.iteration_work(scene_, DetectOptions{variant, diameter_, threads, nullptr});
}

std::pair<std::uint64_t, std::uint64_t> DetectionKernel::wrong_results() {
  if (!have_reference_) {
    // Its own detector, so that the last run's contacts stay in detector_.
    ContactDetector exact;
    exact.run(scene_,
              DetectOptions{parse_variant("particle/sorted/half/static"), diameter_, 0, nullptr});
    reference_ = exact.canonical_contacts();
    have_reference_ = true;
  }
  return contact_differences(reference_, detector_.canonical_contacts());
}

}  // namespace contactlab::tuner
