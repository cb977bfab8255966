// Writing an output file so that a failure never leaves it half-written or destroys the old one.
#pragma once

#include <functional>
#include <ostream>
#include <string>

namespace contactlab {

// Calls `write` on a stream to a temporary file beside `path`, then renames it onto `path`.
// `path`'s missing folders are made first (prepare_output_file). On any error (from `write` or
// from the stream) the temporary file is removed, `path` is untouched, and InputError is thrown
// naming the file.
void write_file_atomically(const std::string& path, const std::function<void(std::ostream&)>& write,
                           bool binary = false);

// Makes `path`'s folder and the folders above it that are missing, as `mkdir -p` does, then
// throws InputError unless that folder is writable and `path` is not itself a folder. The one
// place output folders are made: the programs call it for every output path before a long run,
// so that an impossible path (a file where a folder should be, no permission) fails at once
// rather than after the work. The message is one line naming `path` and the reason.
void prepare_output_file(const std::string& path);

}  // namespace contactlab
