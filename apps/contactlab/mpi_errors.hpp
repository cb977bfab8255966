// How the MPI paths of the commands end on an error (built only with MPI): runs `body` (the
// whole command) and turns agreed errors into one message. An InputError is printed by the rank
// that reports it (mpi::run_checked chose one) before MPI_Finalize, and the barrier holds the
// others until it has, because mpirun ends the job at the first non-zero exit; anything else may
// have left other ranks inside a collective, so it aborts every rank with the message.
#pragma once

#include <fmt/core.h>
#include <mpi.h>

#include <cstdio>
#include <exception>

#include "contactlab/kernels/error.hpp"
#include "contactlab/mpi/runtime.hpp"

namespace contactlab::cli {

template <class Body>
int with_agreed_errors(MPI_Comm comm, const Body& body) {
  try {
    return body();
  } catch (const InputError& e) {
    fmt::print(stderr, "contactlab: error: {}\n", e.what());
    std::fflush(stderr);
    MPI_Barrier(comm);
    throw ReportedElsewhere();
  } catch (const ReportedElsewhere&) {
    MPI_Barrier(comm);
    throw;
  } catch (const std::exception& e) {
    mpi::abort_all(comm, e.what(), 2);
  }
}

}  // namespace contactlab::cli
