// tridex command — transparent huge pages for the big arrays.
//
// Why: the command's arrays are big (a 5000² Z-map is 100 MB, a 5 M-move program's moves 800 MB)
// and written once, right after allocation. With 4 KiB pages every first touch of a page is a
// fault; on the 2-core VM this project is measured on a fault costs ~25 µs, so the model-D-like
// run (bench/backends.md) spent more time faulting than parsing or dexelizing: 54 s in all with
// 4 KiB pages, 34 s with 2 MiB ones (same machine, back to back). Linux gives an anonymous
// mapping 2 MiB pages when it is marked MADV_HUGEPAGE (transparent_hugepage "madvise" mode, the
// default of Debian's kernels; in "always" mode it does so anyway, in "never" not at all).
#pragma once

#include <cstddef>

namespace tridex::cli {

// Blocks smaller than this keep ordinary pages: they are faulted in a few times at most, and
// marking many small ranges would split the heap into many kernel mappings.
inline constexpr std::size_t kHugePageBlockBytes = std::size_t{8} << 20;

// Marks the whole 2 MiB pages inside [block, block + bytes) MADV_HUGEPAGE, when the block is at
// least kHugePageBlockBytes and TRIDEX_HUGE_PAGES is not "0". The block must be anonymous
// memory this process owns and has not touched yet (fresh from malloc). Returns whether it
// marked anything; failure (an old kernel, no THP) only means ordinary pages.
bool advise_huge_pages(void* block, std::size_t bytes);

}  // namespace tridex::cli
