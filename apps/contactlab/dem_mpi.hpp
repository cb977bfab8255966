// `dem run --mpi`: what the dem command hands to its MPI path (dem_mpi.cpp, built only with
// MPI).
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>

#include "dem_outputs.hpp"

namespace contactlab::cli {

struct DemMpiRequest {
  std::string config;
  int threads = 0;
  std::uint64_t steps = 0;             // 0: to the config's end
  std::optional<double> until_time_s;  // absolute simulated time; unset: the config's end
  double until_discharged = 0.0;       // 0: off
  std::string axis;                    // empty: the longest
  double rebalance_margin = 0.1;  // re-cut the slabs when the largest work exceeds the mean by it
  std::string variant;            // a force variant by name; empty: the config's
  std::string json_out;
  // Frames, pictures, the discharge CSV and the checkpoint, written by rank 0 from the run
  // gathered at every output step: the files one process would have written.
  DemOutputOptions outputs;
  std::string restart;  // a checkpoint of the config, from any run (one process or any ranks)
  // --resume: continue from this file when it exists (rank 0 looks), else start; it is the
  // checkpoint (outputs.checkpoint), written at outputs, every resume_every_s and on a signal.
  std::string resume;
  double resume_every_s = 600.0;
  double progress_every_s = 0.0;  // rank 0's progress lines on stderr (0: none)
  std::string command_line;
  std::function<void()> check_options;  // run on every rank; throws InputError
};

// Initialises MPI and runs the config decomposed into slabs over every rank of MPI_COMM_WORLD
// (dem/slabs.hpp, dem_mpi/halo_exchange.hpp); rank 0 prints the run and the per-rank phase
// times and writes --json. A bad config ends every rank with one message; a failure inside the
// run (an unstable particle, out of memory) aborts every rank with the failing rank's message.
int run_dem_mpi(const DemMpiRequest& request);

}  // namespace contactlab::cli
