// A fixed-size array whose start is staggered by a per-array offset within a
// 4 KiB page. Big SoA arrays allocated with mmap all start at the same page
// offset; a kernel streaming a dozen of them then maps every stream to the
// same L1 sets (4 KiB aliasing) and can slow down several-fold. Giving array
// k the offset 64*(5k mod 64) bytes spreads the streams over the sets.
//
// Arrays of 4 MiB and more are asked to sit on 2 MiB pages (transparent huge
// pages, madvise mode on Debian 12): a step over 10^6 particles otherwise
// walks ~40 000 4 KiB pages of particle columns, plus the grid's rows, per
// pass. Measured gain is small, 1-3 % of a 2D linear step at 10^6
// particles (docs/performance.md, "Huge pages for large arrays"). The
// stagger stays an offset within the first 4 KiB, so the aliasing argument
// above holds.
#pragma once

#include <sys/mman.h>

#include <algorithm>
#include <cstddef>
#include <cstdlib>
#include <cstring>
#include <new>
#include <type_traits>
#include <utility>

namespace mmpm {

template <class T>
class StaggeredArray {
  static_assert(std::is_trivially_copyable_v<T>);
  static constexpr std::size_t kHugePage = std::size_t(2) << 20;
  static constexpr std::size_t kHugeMinBytes = std::size_t(4) << 20;

 public:
  StaggeredArray() = default;
  StaggeredArray(std::size_t n, int slot) { allocate(n, slot); }
  StaggeredArray(const StaggeredArray& o) : StaggeredArray(o.size_, o.slot_) {
    if (size_) std::memcpy(data_, o.data_, size_ * sizeof(T));
  }
  StaggeredArray(StaggeredArray&& o) noexcept { swap(o); }
  StaggeredArray& operator=(StaggeredArray o) noexcept {
    swap(o);
    return *this;
  }
  ~StaggeredArray() { std::free(raw_); }

  void allocate(std::size_t n, int slot) {
    std::free(raw_);
    slot_ = slot;
    size_ = n;
    const std::size_t offset = std::size_t(64) * std::size_t((5 * slot) % 64);
    const bool huge = offset + n * sizeof(T) >= kHugeMinBytes;
    const std::size_t page = huge ? kHugePage : 4096;
    // 4 KiB of slack after the data, then whole pages (aligned_alloc's rule).
    const std::size_t bytes = (offset + n * sizeof(T) + 4096 + page - 1) / page * page;
    raw_ = static_cast<unsigned char*>(std::aligned_alloc(page, bytes));
    if (!raw_) throw std::bad_alloc();
    // Advice only: where the kernel has no huge pages the array keeps 4 KiB ones.
    if (huge) (void)madvise(raw_, bytes, MADV_HUGEPAGE);
    data_ = reinterpret_cast<T*>(raw_ + offset);
    std::memset(static_cast<void*>(data_), 0, n * sizeof(T));
  }
  void swap(StaggeredArray& o) noexcept {
    std::swap(raw_, o.raw_);
    std::swap(data_, o.data_);
    std::swap(size_, o.size_);
    std::swap(slot_, o.slot_);
  }
  // Exchanges only the storage, keeping each array's slot bookkeeping honest.
  void swap_storage(StaggeredArray& o) noexcept { swap(o); }

  T* data() { return data_; }
  const T* data() const { return data_; }
  std::size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  T& operator[](std::size_t i) { return data_[i]; }
  const T& operator[](std::size_t i) const { return data_[i]; }
  void fill(T v) { std::fill(data_, data_ + size_, v); }

 private:
  unsigned char* raw_ = nullptr;
  T* data_ = nullptr;
  std::size_t size_ = 0;
  int slot_ = 0;
};

}  // namespace mmpm
