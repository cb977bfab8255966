#include "contactlab/tuner_dem/step_emulation.hpp"

#include "contactlab/kernels/error.hpp"
#include "contactlab/tuner_model/emulation.hpp"

namespace contactlab::dem {

std::vector<EmulatedStep> emulate_steps(const ForceLoopWork& work, const ForceVariant& variant,
                                        const ForceCosts& costs, const MeasuredStep& one,
                                        const MeasuredStep& widest,
                                        const std::vector<int>& threads) {
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
    steps.push_back({t, neighbor.at(t), scale * predict_force_pass(work, variant, t, costs).seconds,
                     integrate.at(t)});
  }
  return steps;
}

}  // namespace contactlab::dem
