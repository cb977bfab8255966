// `detect --mpi` and `tune --mpi`: what the commands hand to their MPI paths (detect_mpi.cpp,
// built only with MPI).
#pragma once

#include <cstdint>
#include <functional>
#include <string>

#include "cli_shared.hpp"
#include "contactlab/tuner/tune.hpp"

namespace contactlab::cli {

struct MpiDetectRequest {
  MpiCliOptions mpi;
  const SceneOptions* scene = nullptr;
  std::string variant;     // or auto: each rank's part tuned (mpi_tuning.hpp)
  std::string cache_file;  // tuning cache for auto
  int threads = 0;
  int warmup = 0;  // untimed runs, then `repeat` timed ones (the slowest rank of each)
  int repeat = 1;
  std::string contacts_out;
  std::string json_out;
  std::string command_line;
  std::function<void()> check_options;  // run on every rank; throws InputError
};

// Initialises MPI, runs the detection on every rank of MPI_COMM_WORLD, prints the per-rank
// table and the maxima on rank 0, writes the result file from rank 0. Errors on any rank end
// every rank: the reporting rank throws InputError, the others ReportedElsewhere.
int run_detect_mpi(const MpiDetectRequest& request);

// `tune --mpi`: what the tune command hands to its MPI path.
struct MpiTuneRequest {
  MpiCliOptions mpi;
  const SceneOptions* scene = nullptr;
  std::string cache_file;
  std::string json_out;
  std::string command_line;
  bool recalibrate = false;
  std::function<void()> check_options;                    // run on every rank; throws InputError
  std::function<tuner::TuneOptions()> options;            // the tuner's options; throws InputError
  std::function<void(const tuner::TuneDocument&)> print;  // rank 0 prints the report
};

// Initialises MPI, tunes every rank's part of the detection together (mpi_tuning.hpp); rank 0
// prints the report, stores the choice in the tuning cache and writes --json. Errors as
// run_detect_mpi.
int run_tune_mpi(const MpiTuneRequest& request);

}  // namespace contactlab::cli
