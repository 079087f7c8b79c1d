// An allocator for buffers of megabytes: images, per-texel arrays, ray-scene arrays.
//
// Why. A fresh buffer is backed by memory only when first touched, one page fault per
// page: 512 traps into the kernel per 2 MiB with 4 KiB pages, and each trap is dear under
// virtualisation. A bake at 2048² touches ~300 MB of new buffers per call; measured on the
// 2-core CI machine (docs/benchmarks.md, "bake: huge pages"), the faults were a fifth of
// the call. Linux gives transparent huge pages (2 MiB, one fault each) to memory that asks
// for them (/sys/kernel/mm/transparent_hugepage/enabled = madvise, Debian's default): a
// block aligned to 2 MiB and advised MADV_HUGEPAGE before its first touch.
//
// Guarantees: the memory is that of std::allocator (only the backing pages differ); blocks
// under kHugePageThreshold are ordinary operator new allocations; where the kernel refuses
// the advice (THP off, another OS) the block is an ordinary aligned allocation. One
// difference in contents: elements made without a value (LargeVector<T>(n), resize(n)) are
// default-initialised, as by new T[n], so trivial types (float, int) are left unwritten. A
// buffer that is then filled in parallel is first touched, and its pages faulted in, by the
// threads that fill it, not zeroed first by one thread (a 2 GiB distance field: the serial
// zeroing was a quarter of the build). Pass a value (v(n, 0.0f), assign) to have it filled.
#pragma once

#include <cstddef>
#include <new>
#include <type_traits>
#include <utility>
#include <vector>

namespace meso {

// Below this size a buffer is allocated as usual (the rounding to 2 MiB would waste more
// than the faults cost).
inline constexpr size_t kHugePageThreshold = size_t(4) << 20;

void* huge_page_allocate(size_t bytes);
void huge_page_deallocate(void* p, size_t bytes) noexcept;

template <class T>
struct HugePageAllocator {
  static_assert(alignof(T) <= alignof(std::max_align_t), "over-aligned types need their own allocator");
  using value_type = T;
  HugePageAllocator() noexcept = default;
  template <class U>
  HugePageAllocator(const HugePageAllocator<U>&) noexcept {}
  T* allocate(size_t n) {
    if (n > static_cast<size_t>(-1) / sizeof(T)) throw std::bad_array_new_length();
    return static_cast<T*>(huge_page_allocate(n * sizeof(T)));
  }
  void deallocate(T* p, size_t n) noexcept { huge_page_deallocate(p, n * sizeof(T)); }
  // Made without a value: default-initialised (see above). With values: as std::allocator.
  template <class U>
  void construct(U* p) noexcept(std::is_nothrow_default_constructible_v<U>) {
    ::new (static_cast<void*>(p)) U;
  }
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
  template <class U>
  bool operator==(const HugePageAllocator<U>&) const noexcept { return true; }
  template <class U>
  bool operator!=(const HugePageAllocator<U>&) const noexcept { return false; }
};

// A std::vector whose large blocks come in huge pages.
template <class T>
using LargeVector = std::vector<T, HugePageAllocator<T>>;

}  // namespace meso
