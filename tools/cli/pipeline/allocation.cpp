// tridex command — the process's operator new: malloc, plus huge pages for big blocks.
//
// Every big array of the command (moves, Z-maps, dexels, meshes) is a std::vector, so replacing
// the one replaceable `operator new(std::size_t)` reaches all of them; libstdc++'s array and
// nothrow forms call it. Blocks come from malloc and go back with free, as the default's do.
// Linked into the command only: a program that embeds the kernel keeps its own allocator.
// Not under the sanitizers, whose own operator new checks new/delete pairing.
#include <cstdlib>
#include <new>

#include "pipeline/huge_pages.hpp"

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define TRIDEX_SANITIZED_ALLOCATOR 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer) || \
    __has_feature(memory_sanitizer)
#define TRIDEX_SANITIZED_ALLOCATOR 1
#endif
#endif

#ifndef TRIDEX_SANITIZED_ALLOCATOR

void* operator new(std::size_t bytes) {
  void* block = nullptr;
  while ((block = std::malloc(bytes == 0 ? 1 : bytes)) == nullptr) {
    std::new_handler handler = std::get_new_handler();  // as the standard's default does
    if (handler == nullptr) throw std::bad_alloc();
    handler();
  }
  tridex::cli::advise_huge_pages(block, bytes);
  return block;
}

void operator delete(void* block) noexcept { std::free(block); }
void operator delete(void* block, std::size_t) noexcept { std::free(block); }

#endif
