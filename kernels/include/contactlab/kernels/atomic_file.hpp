// Writing an output file so that a failure never leaves it half-written or destroys the old one.
#pragma once

#include <functional>
#include <ostream>
#include <string>

namespace contactlab {

// Calls `write` on a stream to a temporary file beside `path`, then renames it onto `path`.
// On any error (from `write` or from the stream) the temporary file is removed, `path` is
// untouched, and InputError is thrown naming the file.
void write_file_atomically(const std::string& path, const std::function<void(std::ostream&)>& write,
                           bool binary = false);

// Throws InputError unless `path`'s directory exists and is writable: checked before long
// runs so that a typo in an output path fails at once rather than after the work.
void check_writable(const std::string& path);

}  // namespace contactlab
