#include "contactlab/kernels/atomic_file.hpp"

#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "contactlab/kernels/error.hpp"

namespace contactlab {

namespace {

// Why `dir` could not be made (`error`: what creating it reported): the nearest of it and the
// folders above it that exists but is not a folder, when there is one.
std::string why_not_made(const std::filesystem::path& dir, const std::error_code& error) {
  namespace fs = std::filesystem;
  for (fs::path p = dir; !p.empty(); p = p.parent_path()) {
    std::error_code ignored;
    const fs::file_status status = fs::status(p, ignored);
    if (fs::is_directory(status)) break;
    if (fs::exists(status)) {
      std::string why(1, '\'');  // not "'" + p.string(): GCC 12 then warns (-Wrestrict)
      why += p.string();
      why += fs::is_regular_file(status) ? "' is a file, not a folder" : "' is not a folder";
      return why;
    }
    if (p == p.parent_path()) break;  // the root
  }
  return error.message();
}

}  // namespace

void prepare_output_file(const std::string& path) {
  namespace fs = std::filesystem;
  const fs::path target(path);
  const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path(".");
  std::error_code error;
  if (!fs::is_directory(dir, error)) {
    fs::create_directories(dir, error);
    // The standard lets create_directories succeed where `dir` exists as a file.
    std::error_code ignored;
    if (error || !fs::is_directory(dir, ignored)) {
      throw InputError(path + ": cannot create the folder '" + dir.string() +
                       "': " + why_not_made(dir, error));
    }
  }
  if (::access(dir.c_str(), W_OK) != 0) {
    throw InputError(path + ": folder '" + dir.string() + "' is not writable");
  }
  if (fs::is_directory(target, error)) throw InputError(path + ": is a folder");
}

void write_file_atomically(const std::string& path, const std::function<void(std::ostream&)>& write,
                           bool binary) {
  prepare_output_file(path);
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
