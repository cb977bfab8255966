// "A kernel" as the tuner sees it: something that runs one variant of itself on its scene and
// reports named phase times and work counts, tells the schedule model the exact work of each
// parallel iteration, and says how many of its results a variant got wrong. Contact detection
// is one (DetectionKernel); DEM's force loop will be another, tuned by the same methods.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "contactlab/kernels/contact_list.hpp"
#include "contactlab/kernels/detector.hpp"
#include "contactlab/kernels/scene.hpp"
#include "contactlab/kernels/variant.hpp"
#include "contactlab/tuner_model/output_cost.hpp"

namespace contactlab::tuner {

struct KernelRun {
  std::vector<std::pair<std::string, double>> phases_s;       // in run order
  std::vector<std::pair<std::string, std::uint64_t>> counts;  // work done
  double phase_s(std::string_view name) const;                // 0 when absent
};

class MeasuredKernel {
 public:
  virtual ~MeasuredKernel() = default;
  virtual std::string_view name() const = 0;
  // The phase the tuner minimises: the one the variant's schedule parallelises.
  virtual std::string_view tuned_phase() const = 0;
  virtual KernelRun run(const Variant& variant, int threads) = 0;
  // The exact work of each iteration of the variant's parallel loop (no timing).
  virtual LoopWork iteration_work(const Variant& variant, int threads) = 0;
  // Results of the last run that differ from the exact reference: {missing, extra}.
  virtual std::pair<std::uint64_t, std::uint64_t> wrong_results() = 0;
  // The output (its entries and their degree), estimated without a timed run, for the model's
  // output term (output_cost.hpp); no entries: no such term.
  virtual OutputEstimate estimated_output() { return {}; }
  // The share of the output's entries a run of `variant` copies after the loop (the output
  // cost is priced and calibrated per copied entry). All of them, unless the kernel writes
  // some rows in place.
  virtual double copied_output_share(const Variant& /*variant*/, int /*threads*/) { return 1.0; }

  // A kernel run by several processes together (MPI ranks, each on its own part) is as fast as
  // its slowest part, and every part must take the same decisions (the same runs in the same
  // order). The tuner passes what it decides by but does not measure through these: predicted
  // times (replaced by their maximum over the parts) and values computed from a part's own work
  // (replaced by the first part's). A kernel of one process leaves them as they are; run() and
  // wrong_results() of a kernel of several return what holds for all its parts.
  virtual void max_over_parts(std::span<double> /*values*/) {}
  virtual void from_first_part(std::span<int> /*values*/) {}

  // `count` timed runs of the tuned phase (after whatever warm-up the caller did).
  std::vector<double> samples(const Variant& variant, int threads, int count);
};

// Contact detection of one scene: phases "setup" (T_s) and "detect" (T_c, tuned), and within
// T_c "assembly" (the contact lists' rows written after the loop: T_c less the slowest thread's
// loop); counts "candidate_tests" and "contact_pairs"; the reference is the exact
// particle/sorted/half run. Its output: both partner lists, two entries per contact, and their
// entry-weighted degree, estimated from a stratified sample of homes (every 16th particle in
// cell order, full stencil: their rows are exact); a restricted kernel (one MPI rank's part)
// estimates none.
//
// `base` restricts the homes (HomeRange, HomeBlocks: one MPI rank's part of the detection; its
// variant, diameter and threads are ignored); the reference then has the same homes and the
// variant's loop, order and stencil (which decide, with homes, which pairs a part lists), so
// only single precision can differ from it.
class DetectionKernel final : public MeasuredKernel {
 public:
  DetectionKernel(const Scene& scene, double diameter) : scene_(scene), diameter_(diameter) {}
  DetectionKernel(const Scene& scene, double diameter, const DetectOptions& base)
      : scene_(scene), diameter_(diameter), homes_(base.homes), blocks_(base.blocks) {}
  std::string_view name() const override { return "contact_detection"; }
  std::string_view tuned_phase() const override { return "detect"; }
  KernelRun run(const Variant& variant, int threads) override;
  LoopWork iteration_work(const Variant& variant, int threads) override;
  std::pair<std::uint64_t, std::uint64_t> wrong_results() override;
  OutputEstimate estimated_output() override;
  double copied_output_share(const Variant& variant, int threads) override {
    return contactlab::copied_output_share(variant, threads);
  }
  // Runs from now on visit only these blocks of the loop (a thread's or a rank's share, timed
  // alone), with the same buffers: no fresh memory to fault in.
  void set_blocks(const HomeBlocks& blocks) {
    blocks_ = blocks;
    have_reference_ = false;
    output_.reset();
  }

 private:
  DetectOptions options_for(const Variant& variant, int threads) const;
  bool restricted() const {
    return homes_.first != 0 || homes_.last != UINT32_MAX || blocks_.block;
  }

  const Scene& scene_;
  double diameter_;
  HomeRange homes_{};
  HomeBlocks blocks_{};
  ContactDetector detector_;
  ContactList reference_;
  std::string reference_structure_;  // restricted homes: the structure of the reference
  Variant last_;                     // the variant of the last run
  bool have_reference_ = false;
  std::optional<OutputEstimate> output_;  // estimated once
};

}  // namespace contactlab::tuner
