// `detect --mpi`: what the detect command hands to its MPI path (detect_mpi.cpp, built only
// with MPI).
#pragma once

#include <cstdint>
#include <functional>
#include <string>

#include "cli_shared.hpp"

namespace contactlab::cli {

struct MpiDetectRequest {
  std::string mode;  // replicated or decomposed
  std::uint32_t block = 200;
  double halo = 0.0;
  const SceneOptions* scene = nullptr;
  std::string variant;
  int threads = 0;
  std::string contacts_out;
  std::string json_out;
  std::string command_line;
  std::function<void()> check_options;  // run on every rank; throws InputError
};

// Initialises MPI, runs the detection on every rank of MPI_COMM_WORLD, prints the per-rank
// table and the maxima on rank 0, writes the result file from rank 0. Errors on any rank end
// every rank: the reporting rank throws InputError, the others ReportedElsewhere.
int run_detect_mpi(const MpiDetectRequest& request);

}  // namespace contactlab::cli
