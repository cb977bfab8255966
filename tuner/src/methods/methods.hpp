// The registered tuning methods' constructors (tuner/src/methods/*.cpp) and what they share.
#pragma once

#include <cstddef>
#include <memory>
#include <span>
#include <vector>

#include "contactlab/tuner/measured_kernel.hpp"
#include "contactlab/tuner/tuning_method.hpp"

namespace contactlab::tuner {

std::unique_ptr<TuningMethod> make_model_method();
std::unique_ptr<TuningMethod> make_search_method();
std::unique_ptr<TuningMethod> make_exhaustive_method();

// Every loop/order/stencil/precision the options allow, with a placeholder schedule.
std::vector<Variant> structures_of(const TuneOptions& options);

// The chunk grid that leaves every thread enough chunks (balanced_chunk_grid), bounded by the
// largest part's iterations: a kernel run by several processes (MPI ranks) prices and measures
// every candidate collectively, so every part must hold the same grid.
std::vector<int> chunk_grid_of(MeasuredKernel& kernel, std::span<const int> grid,
                               std::size_t iterations, int threads);

}  // namespace contactlab::tuner
