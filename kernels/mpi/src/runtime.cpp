// Session, error agreement and the byte exchanges of runtime.hpp.
#include "contactlab/mpi/runtime.hpp"

#include <fmt/core.h>
#include <sys/resource.h>

#include <climits>
#include <new>
#include <numeric>
#ifdef __SANITIZE_ADDRESS__
#include <sanitizer/lsan_interface.h>
#endif

#include "contactlab/kernels/error.hpp"

namespace contactlab::mpi {

Session::Session(int* argc, char*** argv) {
  int initialised = 0;
  MPI_Initialized(&initialised);
  if (initialised) return;
  int provided = 0;
  {
#ifdef __SANITIZE_ADDRESS__
    // Open MPI keeps part of what MPI_Init allocates until the process ends, much of it in
    // plugins it unloads at MPI_Finalize (LeakSanitizer then cannot name them, so no
    // suppression file can): not ours to free, so not reported.
    const __lsan::ScopedDisabler open_mpi_keeps_its_state;
#endif
    MPI_Init_thread(argc, argv, MPI_THREAD_FUNNELED, &provided);
  }
  owns_ = true;
}

Session::~Session() {
  if (!owns_) return;
  int finalised = 0;
  MPI_Finalized(&finalised);
  if (finalised) return;
#ifdef __SANITIZE_ADDRESS__
  const __lsan::ScopedDisabler open_mpi_keeps_its_state;  // as in MPI_Init above
#endif
  MPI_Finalize();
}

int rank_of(MPI_Comm comm) {
  int rank = 0;
  MPI_Comm_rank(comm, &rank);
  return rank;
}

int size_of(MPI_Comm comm) {
  int size = 1;
  MPI_Comm_size(comm, &size);
  return size;
}

void run_checked(MPI_Comm comm, const std::function<void()>& phase) {
  std::string message;
  bool failed = false;
  bool elsewhere = false;
  try {
    phase();
  } catch (const ReportedElsewhere&) {
    failed = elsewhere = true;
  } catch (const InputError& e) {
    failed = true;
    message = e.what();
  } catch (const std::bad_alloc&) {
    failed = true;
    message = "out of memory";
  } catch (const std::exception& e) {
    failed = true;
    message = e.what();
  }
  // The lowest rank with its own message reports; INT_MAX = nobody failed.
  int mine = failed && !elsewhere ? rank_of(comm) : INT_MAX;
  int any = failed ? 1 : 0;
  int first = INT_MAX, count = 0;
  MPI_Allreduce(&mine, &first, 1, MPI_INT, MPI_MIN, comm);
  MPI_Allreduce(&any, &count, 1, MPI_INT, MPI_SUM, comm);
  if (count == 0) return;
  if (first == rank_of(comm)) throw InputError(message);
  throw ReportedElsewhere();
}

void abort_all(MPI_Comm comm, const std::string& message, int code) {
  fmt::print(stderr, "contactlab: error (rank {}): {}; aborting every rank\n", rank_of(comm),
             message);
  std::fflush(stderr);
  MPI_Abort(comm, code);
  std::abort();  // MPI_Abort does not return
}

std::uint64_t peak_rss_bytes() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<std::uint64_t>(usage.ru_maxrss) * 1024;  // Linux reports KiB
}

namespace {

int as_int(std::uint64_t count) {
  if (count > static_cast<std::uint64_t>(INT_MAX)) {
    throw InputError("an MPI exchange of " + std::to_string(count) +
                     " bytes exceeds 2 GiB; use more processes");
  }
  return static_cast<int>(count);
}

// Exchanges the byte counts: sent[r] = bytes for rank r; returns the counts from each rank.
std::vector<std::uint64_t> exchange_counts(MPI_Comm comm,
                                           const std::vector<std::vector<char>>& bytes) {
  const int ranks = size_of(comm);
  std::vector<std::uint64_t> sent(ranks), received(ranks);
  for (int r = 0; r < ranks; ++r) sent[r] = bytes[r].size();
  MPI_Alltoall(sent.data(), 1, MPI_UINT64_T, received.data(), 1, MPI_UINT64_T, comm);
  return received;
}

}  // namespace

std::vector<char> all_to_all_bytes(MPI_Comm comm, const std::vector<std::vector<char>>& bytes,
                                   std::vector<std::uint64_t>* received_counts) {
  const int ranks = size_of(comm);
  const std::vector<std::uint64_t> from = exchange_counts(comm, bytes);
  std::vector<int> send_counts(ranks), send_displs(ranks), recv_counts(ranks), recv_displs(ranks);
  std::vector<char> send, received;
  run_checked(comm, [&] {
    std::uint64_t out = 0, in = 0;
    for (int r = 0; r < ranks; ++r) {
      send_counts[r] = as_int(bytes[r].size());
      send_displs[r] = as_int(out);
      out += bytes[r].size();
      recv_counts[r] = as_int(from[r]);
      recv_displs[r] = as_int(in);
      in += from[r];
    }
    as_int(out);
    as_int(in);
    send.resize(out);
    received.resize(in);
    for (int r = 0; r < ranks; ++r) {
      std::copy(bytes[r].begin(), bytes[r].end(), send.begin() + send_displs[r]);
    }
  });
  MPI_Alltoallv(send.data(), send_counts.data(), send_displs.data(), MPI_BYTE, received.data(),
                recv_counts.data(), recv_displs.data(), MPI_BYTE, comm);
  if (received_counts) *received_counts = from;
  return received;
}

std::vector<char> exchange_with_neighbours(MPI_Comm comm,
                                           const std::vector<std::vector<char>>& bytes) {
  const int ranks = size_of(comm);
  const std::vector<std::uint64_t> from = exchange_counts(comm, bytes);
  std::vector<char> received;
  std::vector<std::uint64_t> offset(ranks + 1, 0);
  run_checked(comm, [&] {
    for (int r = 0; r < ranks; ++r) {
      as_int(bytes[r].size());
      offset[r + 1] = offset[r] + as_int(from[r]);
    }
    received.resize(offset[ranks]);
  });
  constexpr int kTag = 7;
  std::vector<MPI_Request> requests;
  for (int r = 0; r < ranks; ++r) {
    if (from[r] == 0) continue;
    requests.emplace_back();
    MPI_Irecv(received.data() + offset[r], static_cast<int>(from[r]), MPI_BYTE, r, kTag, comm,
              &requests.back());
  }
  for (int r = 0; r < ranks; ++r) {
    if (bytes[r].empty()) continue;
    requests.emplace_back();
    MPI_Isend(bytes[r].data(), static_cast<int>(bytes[r].size()), MPI_BYTE, r, kTag, comm,
              &requests.back());
  }
  MPI_Waitall(static_cast<int>(requests.size()), requests.data(), MPI_STATUSES_IGNORE);
  return received;
}

}  // namespace contactlab::mpi
