#include "contactlab/kernels/atomic_file.hpp"

#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "contactlab/kernels/error.hpp"

namespace contactlab {

void check_writable(const std::string& path) {
  namespace fs = std::filesystem;
  const fs::path target(path);
  const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path(".");
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) {
    throw InputError(path + ": directory '" + dir.string() + "' does not exist");
  }
  if (::access(dir.c_str(), W_OK) != 0) {
    throw InputError(path + ": directory '" + dir.string() + "' is not writable");
  }
  if (fs::is_directory(target, ec)) throw InputError(path + ": is a directory");
}

void write_file_atomically(const std::string& path, const std::function<void(std::ostream&)>& write,
                           bool binary) {
  check_writable(path);
  const std::string temporary = path + ".tmp." + std::to_string(::getpid());
  try {
    std::ofstream out(temporary, binary ? std::ios::binary | std::ios::trunc : std::ios::trunc);
    if (!out) throw InputError(path + ": cannot create temporary file: " + std::strerror(errno));
    write(out);
    out.flush();
    if (!out) throw InputError(path + ": write failed: " + std::strerror(errno));
    out.close();
    std::filesystem::rename(temporary, path);
  } catch (const std::filesystem::filesystem_error& e) {
    std::filesystem::remove(temporary);
    throw InputError(path + ": " + e.code().message());
  } catch (const InputError&) {
    std::error_code ignored;
    std::filesystem::remove(temporary, ignored);
    throw;
  } catch (const std::exception& e) {
    std::error_code ignored;
    std::filesystem::remove(temporary, ignored);
    throw InputError(path + ": " + e.what());
  }
}

}  // namespace contactlab
