#include "meso/core/huge_pages.hpp"

#include <cstdlib>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace meso {

namespace {
constexpr size_t kHugePage = size_t(2) << 20;
}

void* huge_page_allocate(size_t bytes) {
  if (bytes < kHugePageThreshold) return ::operator new(bytes);
  const size_t rounded = (bytes + kHugePage - 1) / kHugePage * kHugePage;
  void* p = std::aligned_alloc(kHugePage, rounded);
  if (!p) throw std::bad_alloc();
#if defined(MADV_HUGEPAGE)
  // Advice only: on refusal the block simply stays in small pages.
  (void)madvise(p, rounded, MADV_HUGEPAGE);
#endif
  return p;
}

void huge_page_deallocate(void* p, size_t bytes) noexcept {
  if (!p) return;
  if (bytes < kHugePageThreshold) {
    ::operator delete(p);
    return;
  }
  std::free(p);
}

}  // namespace meso
