// The parallel --contacts-out writer of distributed_detect.hpp: pairs to the ranks holding
// their i range, a local sort, byte offsets by exclusive scan, one collective MPI-IO write into
// a temporary file, renamed into place by rank 0 once every rank has written.
#include <unistd.h>

#include <algorithm>
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

}  // namespace

void write_pairs_parallel(MPI_Comm comm, std::vector<std::uint64_t> pairs, std::uint64_t n,
                          const std::string& path) {
  const int ranks = size_of(comm);
  const int rank = rank_of(comm);
  std::vector<std::vector<char>> outgoing(ranks);
  run_checked(comm, [&] {
    for (const std::uint64_t pair : pairs) {
      auto& out = outgoing[writer_of(pair >> 32, n, ranks)];
      const char* bytes = reinterpret_cast<const char*>(&pair);
      out.insert(out.end(), bytes, bytes + sizeof pair);
    }
    std::vector<std::uint64_t>().swap(pairs);
  });
  std::vector<char> incoming = all_to_all_bytes(comm, outgoing);
  std::vector<std::vector<char>>().swap(outgoing);

  std::string text;
  run_checked(comm, [&] {
    std::vector<std::uint64_t> mine(incoming.size() / sizeof(std::uint64_t));
    std::memcpy(mine.data(), incoming.data(), incoming.size());
    std::vector<char>().swap(incoming);
    std::sort(mine.begin(), mine.end());  // by i, then j: the serial file's order
    if (rank == 0) text = "i,j\n";
    text.reserve(text.size() + mine.size() * 16);
    for (const std::uint64_t pair : mine) {
      text += std::to_string(pair >> 32);
      text += ',';
      text += std::to_string(pair & 0xffffffffu);
      text += '\n';
    }
  });

  std::uint64_t size = text.size(), offset = 0;
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
  // Collective writes in chunks below 2 GiB, the same number of calls on every rank.
  constexpr std::uint64_t kChunk = std::uint64_t{1} << 30;
  std::uint64_t chunks = (size + kChunk - 1) / kChunk, most = 0;
  MPI_Allreduce(&chunks, &most, 1, MPI_UINT64_T, MPI_MAX, comm);
  int write_code = MPI_SUCCESS;
  for (std::uint64_t c = 0; c < most; ++c) {
    const std::uint64_t begin = std::min(size, c * kChunk);
    const std::uint64_t count = std::min(size, begin + kChunk) - begin;
    const int code =
        MPI_File_write_at_all(file, static_cast<MPI_Offset>(offset + begin), text.data() + begin,
                              static_cast<int>(count), MPI_CHAR, MPI_STATUS_IGNORE);
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
