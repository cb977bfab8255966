#include "contactlab/kernels/partner_buffer.hpp"

#include <sys/mman.h>

#include <algorithm>
#include <cstring>
#include <new>
#include <utility>

namespace contactlab {
namespace detail {

PartnerBuffer::PartnerBuffer(PartnerBuffer&& other) noexcept
    : data_(std::exchange(other.data_, nullptr)),
      size_(std::exchange(other.size_, 0)),
      capacity_(std::exchange(other.capacity_, 0)),
      borrowed_(std::exchange(other.borrowed_, false)) {}

PartnerBuffer& PartnerBuffer::operator=(PartnerBuffer&& other) noexcept {
  if (this != &other) {
    free_own();
    data_ = std::exchange(other.data_, nullptr);
    size_ = std::exchange(other.size_, 0);
    capacity_ = std::exchange(other.capacity_, 0);
    borrowed_ = std::exchange(other.borrowed_, false);
  }
  return *this;
}

PartnerBuffer::~PartnerBuffer() { free_own(); }

void PartnerBuffer::free_own() {
  if (data_ && !borrowed_) ::munmap(data_, capacity_ * sizeof(std::uint32_t));
}

void PartnerBuffer::borrow(std::uint32_t* storage, std::size_t capacity) {
  free_own();
  data_ = storage;
  size_ = 0;
  capacity_ = capacity;
  borrowed_ = true;
}

void PartnerBuffer::stop_borrowing() {
  if (borrowed_) *this = PartnerBuffer();
  size_ = 0;
}

void PartnerBuffer::grow(std::size_t entries) {
  // Whole huge pages once past one; below, 64 KiB steps: a small scene's threads each fault in
  // and zero a few pages, not a 2 MiB page per buffer (16 threads x 2 buffers of a tiny scene
  // had spent more time zeroing huge pages than detecting).
  constexpr std::size_t kHugePage = std::size_t{2} << 20, kSmallStep = std::size_t{64} << 10;
  const std::size_t wanted = std::max(2 * capacity_, entries) * sizeof(std::uint32_t);
  const std::size_t step = wanted < kHugePage ? kSmallStep : kHugePage;
  const std::size_t bytes = (wanted + step - 1) / step * step;
  const std::size_t old_bytes = capacity_ * sizeof(std::uint32_t);
  void* p = data_ && !borrowed_ ? ::mremap(data_, old_bytes, bytes, MREMAP_MAYMOVE)
                                : ::mmap(nullptr, bytes, PROT_READ | PROT_WRITE,
                                         MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (p == MAP_FAILED) throw std::bad_alloc();
  if (borrowed_) {  // what was written so far moves along
    std::memcpy(p, data_, size_ * sizeof(std::uint32_t));
    borrowed_ = false;
  }
  if (bytes >= kHugePage) ::madvise(p, bytes, MADV_HUGEPAGE);  // advice only
  data_ = static_cast<std::uint32_t*>(p);
  capacity_ = bytes / sizeof(std::uint32_t);
}

}  // namespace detail

}  // namespace contactlab
