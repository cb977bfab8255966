// The tuner under MPI (docs/mpi.md, "Tuning"): one rank's detection as the tuner's kernel, the
// calibration shared from rank 0, `--variant auto` and `tune --mpi`. Built only with MPI.
#pragma once

#include <mpi.h>

#include <string>

#include "contactlab/kernels/variant.hpp"
#include "contactlab/mpi/distributed_detect.hpp"
#include "contactlab/tuner/result_schema.hpp"
#include "contactlab/tuner/tune.hpp"

namespace contactlab::cli {

// The cache's calibration (or a new one), read or made by rank 0 only, which alone writes the
// cache (atomically); the others wait for it and receive it. Collective; errors agreed.
tuner::Calibration mpi_calibration(MPI_Comm comm, tuner::TuningCache& cache,
                                   const tuner::TuneOptions& options, int threads,
                                   bool recalibrate);

// Tunes every rank's own part of the detection together (collective): the model sees each
// rank's iteration work and takes its slowest rank's predicted time; every timed run is the
// slowest rank's; so every rank makes the same choices. The report (identical choices on every
// rank; rank 0's costs) records the mode and rank count. Decomposed: the full stencil only.
tuner::TuneReport tune_mpi_part(MPI_Comm comm, const mpi::PreparedRun& prepared,
                                const tuner::SceneRecord& scene, double diameter,
                                tuner::TuneOptions options, const tuner::Calibration& calibration,
                                const std::string& command_line,
                                const mpi::MpiOptions& mpi_options);

// What tells a run's tuning cache entry apart from the serial one's and from other rank counts
// and modes: "mpi decomposed, 4 ranks, halo 0.02" (plus the file's size and time when the scene
// has no checksum, a binary file read in shares).
std::string mpi_cache_setting(const mpi::PreparedRun& prepared, const tuner::SceneRecord& scene,
                              const mpi::MpiOptions& mpi_options);

// `detect --mpi ... --variant auto`: rank 0 looks the choice up in the cache; on a miss every
// rank tunes its part (tune_mpi_part) and rank 0 stores the choice. Collective.
Variant mpi_auto_variant(MPI_Comm comm, const mpi::PreparedRun& prepared,
                         const tuner::SceneRecord& scene, double diameter, int threads,
                         const std::string& cache_file, const std::string& command_line,
                         const mpi::MpiOptions& mpi_options);

}  // namespace contactlab::cli
