// The parallel --contacts-out writer of distributed_detect.hpp: pairs to the ranks holding
// their i range, a local sort, byte offsets by exclusive scan, one collective MPI-IO write into
// a temporary file, renamed into place by rank 0 once every rank has written.
#include <unistd.h>

#include <algorithm>
#include <climits>
#include <cstdio>
#include <cstring>
#include <string>

#include "contactlab/kernels/atomic_file.hpp"
#include "contactlab/kernels/error.hpp"
#include "contactlab/mpi/distributed_detect.hpp"
#include "contactlab/mpi/runtime.hpp"

namespace contactlab::mpi {
namespace {

// The rank writing the rows of particle i: rank q holds ids [q N / P, (q + 1) N / P).
int writer_of(std::uint64_t i, std::uint64_t n, int ranks) {
  // The largest q with q N / P <= i, found from the estimate i P / N.
  int q = static_cast<int>(std::min<std::uint64_t>(i * ranks / std::max<std::uint64_t>(n, 1),
                                                   static_cast<std::uint64_t>(ranks - 1)));
  while (q + 1 < ranks && (std::uint64_t(q) + 1) * n / ranks <= i) ++q;
  while (q > 0 && std::uint64_t(q) * n / ranks > i) --q;
  return q;
}

std::string error_text(int code) {
  char text[MPI_MAX_ERROR_STRING];
  int length = 0;
  MPI_Error_string(code, text, &length);
  return std::string(text, length);
}

// The temporary file's name, chosen by rank 0 (beside the target, so the rename stays on one
// file system) and sent to every rank.
std::string temporary_name(MPI_Comm comm, const std::string& path) {
  std::string name;
  if (rank_of(comm) == 0) {
    name = path + ".tmp." + std::to_string(::getpid());
    std::remove(name.c_str());  // a stale one would keep bytes past the new end
  }
  int length = static_cast<int>(name.size());
  MPI_Bcast(&length, 1, MPI_INT, 0, comm);
  name.resize(length);
  MPI_Bcast(name.data(), length, MPI_CHAR, 0, comm);
  return name;
}

int digits(std::uint64_t v) {
  int d = 1;
  while (v >= 10) {
    v /= 10;
    ++d;
  }
  return d;
}

}  // namespace

void write_pairs_parallel(MPI_Comm comm, std::vector<std::uint64_t> pairs, std::uint64_t n,
                          const std::string& path) {
  const int ranks = size_of(comm);
  const int rank = rank_of(comm);
  // Sorted, the pairs are grouped by the rank writing them (rank q writes an id range), so they
  // are sent from where they are, without a copy per destination.
  std::vector<int> send_counts(ranks, 0), send_displs(ranks, 0);
  run_checked(comm, [&] {
    if (rank == 0) prepare_output_file(path);  // the folder, made if missing
    std::sort(pairs.begin(), pairs.end());
    std::vector<std::uint64_t> counts(ranks, 0);
    for (const std::uint64_t pair : pairs) ++counts[writer_of(pair >> 32, n, ranks)];
    std::uint64_t at = 0;
    for (int r = 0; r < ranks; ++r) {
      if (counts[r] > INT_MAX || at > INT_MAX) {
        throw InputError(path + ": too many contacts for one rank; use more processes");
      }
      send_counts[r] = static_cast<int>(counts[r]);
      send_displs[r] = static_cast<int>(at);
      at += counts[r];
    }
  });
  std::vector<int> recv_counts(ranks, 0), recv_displs(ranks, 0);
  MPI_Alltoall(send_counts.data(), 1, MPI_INT, recv_counts.data(), 1, MPI_INT, comm);
  std::vector<std::uint64_t> mine;
  run_checked(comm, [&] {
    std::uint64_t at = 0;
    for (int r = 0; r < ranks; ++r) {
      if (at > INT_MAX) throw InputError(path + ": too many contacts for one rank");
      recv_displs[r] = static_cast<int>(at);
      at += static_cast<std::uint64_t>(recv_counts[r]);
    }
    mine.resize(at);
  });
  MPI_Alltoallv(pairs.data(), send_counts.data(), send_displs.data(), MPI_UINT64_T, mine.data(),
                recv_counts.data(), recv_displs.data(), MPI_UINT64_T, comm);
  std::vector<std::uint64_t>().swap(pairs);

  // This rank's bytes, counted before formatting so that the text is made (and written) in
  // chunks and never whole.
  const std::string header = rank == 0 ? "i,j\n" : "";
  std::uint64_t size = header.size();
  run_checked(comm, [&] {
    std::sort(mine.begin(), mine.end());  // by i, then j: the serial file's order
    for (const std::uint64_t pair : mine) {
      size += std::uint64_t(digits(pair >> 32)) + digits(pair & 0xffffffffu) + 2;
    }
  });
  std::uint64_t offset = 0;
  MPI_Exscan(&size, &offset, 1, MPI_UINT64_T, MPI_SUM, comm);
  if (rank == 0) offset = 0;  // MPI_Exscan leaves rank 0's result undefined

  const std::string temporary = temporary_name(comm, path);
  MPI_File file = MPI_FILE_NULL;
  const int open_code = MPI_File_open(comm, temporary.c_str(), MPI_MODE_CREATE | MPI_MODE_WRONLY,
                                      MPI_INFO_NULL, &file);
  run_checked(comm, [&] {
    if (open_code != MPI_SUCCESS) {
      throw InputError(path + ": cannot create the output: " + error_text(open_code));
    }
  });
  // Collective writes of up to kChunkPairs formatted pairs each, the same number of calls on
  // every rank.
  constexpr std::uint64_t kChunkPairs = std::uint64_t{1} << 20;
  std::uint64_t chunks = (mine.size() + kChunkPairs - 1) / kChunkPairs, most = 0;
  MPI_Allreduce(&chunks, &most, 1, MPI_UINT64_T, MPI_MAX, comm);
  most = std::max<std::uint64_t>(most, 1);  // the header
  int write_code = MPI_SUCCESS;
  std::string text;
  char number[24];
  for (std::uint64_t c = 0; c < most; ++c) {
    text.clear();
    if (c == 0) text = header;
    const std::uint64_t begin = std::min<std::uint64_t>(mine.size(), c * kChunkPairs);
    const std::uint64_t end = std::min<std::uint64_t>(mine.size(), begin + kChunkPairs);
    for (std::uint64_t k = begin; k < end; ++k) {
      const int a = std::snprintf(number, sizeof number, "%llu,%llu\n",
                                  static_cast<unsigned long long>(mine[k] >> 32),
                                  static_cast<unsigned long long>(mine[k] & 0xffffffffu));
      text.append(number, static_cast<std::size_t>(a));
    }
    const int code =
        MPI_File_write_at_all(file, static_cast<MPI_Offset>(offset), text.data(),
                              static_cast<int>(text.size()), MPI_CHAR, MPI_STATUS_IGNORE);
    offset += text.size();
    if (code != MPI_SUCCESS) write_code = code;
  }
  const int close_code = MPI_File_close(&file);
  auto remove_temporary = [&] {
    if (rank == 0) std::remove(temporary.c_str());
  };
  try {
    run_checked(comm, [&] {
      if (write_code != MPI_SUCCESS) {
        throw InputError(path + ": write failed: " + error_text(write_code));
      }
      if (close_code != MPI_SUCCESS) {
        throw InputError(path + ": write failed: " + error_text(close_code));
      }
    });
    run_checked(comm, [&] {
      if (rank == 0 && std::rename(temporary.c_str(), path.c_str()) != 0) {
        throw InputError(path +
                         ": cannot rename the written file into place: " + std::strerror(errno));
      }
    });
  } catch (...) {
    remove_temporary();
    throw;
  }
}

}  // namespace contactlab::mpi
