// tridex command — transparent huge pages for the big arrays (see huge_pages.hpp).
#include "pipeline/huge_pages.hpp"

#include <cstdint>
#include <cstdlib>
#include <cstring>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace tridex::cli {

namespace {

bool huge_pages_wanted() {
  static const bool wanted = [] {
    const char* value = std::getenv("TRIDEX_HUGE_PAGES");
    return value == nullptr || std::strcmp(value, "0") != 0;
  }();
  return wanted;
}

}  // namespace

bool advise_huge_pages(void* block, std::size_t bytes) {
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  if (block == nullptr || bytes < kHugePageBlockBytes || !huge_pages_wanted()) return false;
  constexpr std::uintptr_t kHugePage = std::uintptr_t{2} << 20;
  const auto begin = reinterpret_cast<std::uintptr_t>(block);
  const std::uintptr_t first = (begin + kHugePage - 1) & ~(kHugePage - 1);
  const std::uintptr_t last = (begin + bytes) & ~(kHugePage - 1);
  if (last <= first) return false;
  return madvise(reinterpret_cast<void*>(first), last - first, MADV_HUGEPAGE) == 0;
#else
  (void)block;
  (void)bytes;
  return false;
#endif
}

}  // namespace tridex::cli
