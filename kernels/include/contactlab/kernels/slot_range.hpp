// A run of consecutive slots of the cell lists: the particles of one or more adjacent cells
// (with the sorted orders also their working ids, so their coordinates are one contiguous
// stretch of each array).
#pragma once

#include <cstdint>

namespace contactlab {

struct SlotRange {
  std::uint32_t begin, end;
};

}  // namespace contactlab
