// A thread's growing list of partners (the detector's per-thread output), in anonymous memory
// that grows by mremap, or in borrowed storage.
#pragma once

#include <cstddef>
#include <cstdint>

namespace contactlab::detail {

// Appends partners without a branch per test: each candidate is written to the next free
// place and the size advances only on contact (a contact is ~1 candidate in 6, so a branch
// would mispredict often). The storage is anonymous memory that grows by mremap: pages move
// without a copy, and only those the owning thread writes are ever touched (a doubling
// vector copied and first-touched about twice the final size, the bulk of a first run's cost).
// It may instead borrow storage (the contact list's own, where a thread's finds are the
// first rows as they are: no copy), and moves to memory of its own if that fills up.
class PartnerBuffer {
 public:
  PartnerBuffer() = default;
  PartnerBuffer(PartnerBuffer&& other) noexcept;
  PartnerBuffer& operator=(PartnerBuffer&& other) noexcept;
  ~PartnerBuffer();

  std::size_t size() const { return size_; }
  std::size_t capacity() const { return capacity_; }
  const std::uint32_t* data() const { return data_; }
  std::uint32_t* data() { return data_; }
  void clear() { size_ = 0; }
  // Empties the buffer and writes to `storage` (room for `capacity` entries, not owned) until
  // it would overflow. Memory of its own is freed.
  void borrow(std::uint32_t* storage, std::size_t capacity);
  // Empties the buffer; if it was borrowing, it has no storage until the next append.
  void stop_borrowing();
  bool borrowing() const { return borrowed_; }
  // Room for `extra` more entries at the end.
  std::uint32_t* tail(std::size_t extra) {
    if (size_ + extra > capacity_) grow(size_ + extra);
    return data_ + size_;
  }
  void advance(std::size_t count) { size_ += count; }

 private:
  void grow(std::size_t entries);
  void free_own();
  std::uint32_t* data_ = nullptr;
  std::size_t size_ = 0, capacity_ = 0;  // entries
  bool borrowed_ = false;                // data_ is not ours to unmap
};

}  // namespace contactlab::detail
