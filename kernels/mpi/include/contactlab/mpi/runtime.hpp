// The MPI runtime contactlab needs: the session (init with threads, finalize), error agreement
// between processes at phase boundaries (so a failure seen by one rank ends every rank with
// one message instead of a hang), typed all-to-all helpers and the peak memory of a process.
#pragma once

#include <mpi.h>

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace contactlab::mpi {

// MPI_Init_thread (funneled: only the main thread calls MPI, OpenMP threads compute) on
// construction, MPI_Finalize on destruction, unless MPI was already initialised by the caller
// (a test's main), in which case neither.
class Session {
 public:
  Session(int* argc, char*** argv);
  ~Session();
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;

 private:
  bool owns_ = false;
};

int rank_of(MPI_Comm comm);
int size_of(MPI_Comm comm);

// Runs `phase` (local work, no communication) and agrees on its outcome with every process of
// `comm` (collective: all call it at the same phase boundary). InputError, bad_alloc and any
// std::exception are caught, so one rank's failure never leaves the others waiting in the
// next collective. When some process failed, every process throws: the lowest failing rank
// InputError with its own message (for it to print), the others ReportedElsewhere
// (error.hpp).
void run_checked(MPI_Comm comm, const std::function<void()>& phase);

// The last resort for an error that escaped the agreement (it may have left other processes
// inside a collective): prints it with the rank and aborts every process.
[[noreturn]] void abort_all(MPI_Comm comm, const std::string& message, int code);

// The peak resident set size of this process (getrusage), in bytes.
std::uint64_t peak_rss_bytes();

// Sends bytes[r] (a concatenation per destination) to every rank; returns what each rank sent
// here, concatenated in rank order, with `received_counts` per source. Counts are exchanged
// first (MPI_Alltoall) and the receive buffer allocated in a checked phase.
std::vector<char> all_to_all_bytes(MPI_Comm comm, const std::vector<std::vector<char>>& bytes,
                                   std::vector<std::uint64_t>* received_counts = nullptr);

// The same exchange, point to point (non-blocking sends and receives to the ranks with
// something to exchange only): the halo, whose partners are a rank's spatial neighbours.
std::vector<char> exchange_with_neighbours(MPI_Comm comm,
                                           const std::vector<std::vector<char>>& bytes);

}  // namespace contactlab::mpi
