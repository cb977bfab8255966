// Helpers of the tests that run the contactlab program under mpiexec.
#pragma once

#include <string>

#include "program_test_support.hpp"

namespace contactlab::test {

// mpiexec with K ranks and the MPI tests' environment. The environment is set on the command
// line, not through CTest, so that it holds however the test is started (as root Open MPI
// refuses to start without OMPI_ALLOW_RUN_AS_ROOT and its confirmation).
inline std::string mpiexec(int ranks) {
  return std::string(CONTACTLAB_MPI_ENV) + " " + mpi_session_environment() + CONTACTLAB_MPIEXEC +
         " -np " + std::to_string(ranks) + " ";
}

// How many times needle occurs in text (overlapping occurrences counted).
inline int count_of(const std::string& text, const std::string& needle) {
  int count = 0;
  for (auto pos = text.find(needle); pos != std::string::npos; pos = text.find(needle, pos + 1)) {
    ++count;
  }
  return count;
}

}  // namespace contactlab::test
