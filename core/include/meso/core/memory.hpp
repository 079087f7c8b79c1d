// The machine's memory, for the guards that refuse work before it runs the machine out of it.
#pragma once

#include <unistd.h>

namespace meso {

// Physical memory in bytes (0 when the system does not say). Header-only: the image module,
// which links no meso library, uses it too.
inline double physical_memory_bytes() {
  const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGE_SIZE);
  return pages > 0 && page > 0 ? static_cast<double>(pages) * static_cast<double>(page) : 0.0;
}

}  // namespace meso
