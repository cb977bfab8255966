// Errors that carry a one-line message meant for the user (bad input, bad options).
#pragma once

#include <charconv>
#include <stdexcept>
#include <string>

namespace contactlab {

// Thrown for anything the user can fix: malformed files, bad parameters, unknown variants.
// The message is one line and names the problem (and the file and line where there is one).
class InputError : public std::runtime_error {
 public:
  explicit InputError(const std::string& message) : std::runtime_error(message) {}
};

// A double as its shortest text that reads back to the same value ("1e-05", "0.005", "inf"),
// for messages: std::to_string's fixed six decimals printed D = 1e-300 as "0.000000".
inline std::string number_text(double value) {
  char text[32];
  const auto result = std::to_chars(text, text + sizeof text, value);
  return {text, result.ptr};
}

}  // namespace contactlab

namespace contactlab {

// An error another process of the same MPI run has already reported: this process exits
// non-zero without printing, so that a failure seen by one rank prints one message.
class ReportedElsewhere : public std::runtime_error {
 public:
  ReportedElsewhere() : std::runtime_error("reported by another process") {}
};

}  // namespace contactlab
