#include "contactlab/tuner_dem/step_emulation.hpp"

#include "contactlab/kernels/error.hpp"
#include "contactlab/tuner_model/emulation.hpp"

namespace contactlab::dem {

StepTraffic step_traffic(std::size_t particles, std::uint64_t pairs) {
  // Per listed pair, streamed from the list once a step: i and j (4 + 4), the image code (1),
  // m* and 1/k_t (8 + 8), the tangential spring read and written (24 + 24). The pair's record
  // (64) stays in L1 within its block; the partner's kinematics block and sums are the
  // partner's own bytes, counted below.
  constexpr double kPerPair = 4 + 4 + 1 + 8 + 8 + 24 + 24;
  // Per particle, the force pass and the drift together (run_steps finishes and drifts a piece
  // of particles while its data is in L1, so each array counts once): the kinematics block read
  // and rewritten (96 + 96), the sums written and read (64 + 64: the finish leaves force,
  // torque, |F| and the contact count in them, not in the particle arrays), 1/m and 1/I read
  // (16), v and w read and written (48 + 48), x read and written (24 + 24), the list build's x0
  // (24), radius and mass (16).
  constexpr double kPerParticle = 96 + 96 + 64 + 64 + 16 + 48 + 48 + 24 + 24 + 24 + 16;
  // Everything a particle has (the block, the sums, about 35 arrays of doubles) and the list's
  // fields per pair.
  constexpr double kParticleFootprint = 96 + 64 + 35 * 8;
  const auto n = static_cast<double>(particles), p = static_cast<double>(pairs);
  return {kPerPair * p + kPerParticle * n,
          static_cast<std::uint64_t>(kParticleFootprint * n + kPerPair * p)};
}

std::vector<EmulatedStep> emulate_steps(const ForceLoopWork& work, const ForceVariant& variant,
                                        const ForceCosts& costs, const MeasuredStep& one,
                                        const MeasuredStep& widest, const std::vector<int>& threads,
                                        const std::optional<tuner::BandwidthCurve>& bandwidth,
                                        const StepTraffic& traffic) {
  if (one.threads != 1) throw InputError("emulate_steps: the anchor must be at one thread");
  const double measured_force = one.per_step.force_s();
  const double predicted_force = predict_force_pass(work, variant, 1, costs).seconds;
  if (!(measured_force > 0.0) || !(predicted_force > 0.0)) {
    throw InputError("emulate_steps: the one-thread force pass took no time");
  }
  const double scale = measured_force / predicted_force;
  auto phase = [&](double at_one, double at_widest) {
    if (widest.threads <= 1 || !(at_one > 0.0) || !(at_widest > 0.0)) {
      return tuner::AmdahlPhase::serial(at_one);
    }
    return tuner::AmdahlPhase::fit(at_one, widest.threads, at_widest);
  };
  const tuner::AmdahlPhase neighbor = phase(one.per_step.neighbor_s, widest.per_step.neighbor_s);
  const tuner::AmdahlPhase integrate = phase(one.per_step.integrate_s, widest.per_step.integrate_s);
  std::vector<EmulatedStep> steps;
  for (const int t : threads) {
    if (t < 1) throw InputError("emulate_steps: thread counts must be >= 1");
    EmulatedStep e{t, neighbor.at(t), scale * predict_force_pass(work, variant, t, costs).seconds,
                   integrate.at(t)};
    if (bandwidth) {
      e.bytes_per_s = bandwidth->at(t);
      e.memory_s = traffic.bytes / e.bytes_per_s;
      const double compute = e.force_s + e.integrate_s;
      const double bound = tuner::roofline_seconds(compute, traffic.bytes, e.bytes_per_s);
      if (bound > compute && compute > 0.0) {
        e.force_s *= bound / compute;
        e.integrate_s *= bound / compute;
      }
    }
    steps.push_back(e);
  }
  return steps;
}

}  // namespace contactlab::dem
