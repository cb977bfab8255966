// What built this binary: recorded in every result file.
#pragma once

#include <string_view>

namespace contactlab {

struct BuildInfo {
  std::string_view version;
  std::string_view compiler;
  std::string_view flags;
  std::string_view build_type;
  bool native;  // compiled with -march=native
  std::string_view git_commit;
  bool git_dirty;  // tracked files differed from the commit at build time
};

const BuildInfo& build_info();

}  // namespace contactlab
