// The registered tuning methods' constructors (tuner/src/methods/*.cpp) and what they share.
#pragma once

#include <memory>
#include <vector>

#include "contactlab/tuner/tuning_method.hpp"

namespace contactlab::tuner {

std::unique_ptr<TuningMethod> make_model_method();
std::unique_ptr<TuningMethod> make_search_method();
std::unique_ptr<TuningMethod> make_exhaustive_method();

// Every loop/order/stencil/precision the options allow, with a placeholder schedule.
std::vector<Variant> structures_of(const TuneOptions& options);

}  // namespace contactlab::tuner
