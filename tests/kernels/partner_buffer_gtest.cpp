// The detector's per-thread partner buffer (partner_buffer.hpp): borrowed storage, then memory
// of its own with what was written.
#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "contactlab/kernels/partner_buffer.hpp"

namespace contactlab::test {
namespace {

TEST(PartnerBuffer, BorrowedStorageIsUsedUntilItFillsThenLeftWithItsContents) {
  std::vector<std::uint32_t> storage(16, 0);
  detail::PartnerBuffer buffer;
  buffer.borrow(storage.data(), storage.size());
  std::uint32_t* place = buffer.tail(10);
  EXPECT_EQ(place, storage.data());
  for (std::uint32_t i = 0; i < 10; ++i) place[i] = 100 + i;
  buffer.advance(10);
  EXPECT_TRUE(buffer.borrowing());
  place = buffer.tail(10);  // 20 entries do not fit in 16
  EXPECT_FALSE(buffer.borrowing());
  EXPECT_NE(buffer.data(), storage.data());
  for (std::uint32_t i = 0; i < 10; ++i) EXPECT_EQ(buffer.data()[i], 100 + i);
  place[0] = 7;
  buffer.advance(1);
  EXPECT_EQ(buffer.size(), 11u);
  EXPECT_EQ(storage[10], 0u);  // the borrowed storage past what was written is untouched

  buffer.borrow(storage.data(), storage.size());
  EXPECT_EQ(buffer.size(), 0u);
  buffer.stop_borrowing();
  EXPECT_FALSE(buffer.borrowing());
  EXPECT_EQ(buffer.size(), 0u);
  buffer.tail(1)[0] = 5;  // memory of its own again
  buffer.advance(1);
  EXPECT_NE(buffer.data(), storage.data());
  EXPECT_EQ(buffer.data()[0], 5u);
}

}  // namespace
}  // namespace contactlab::test
