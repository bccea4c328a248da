#include "core/support/page_memory.h"

#include <new>

#if defined(__has_feature)
#if __has_feature(address_sanitizer)
#define KG_UNDER_ASAN 1
#endif
#endif
#if defined(__SANITIZE_ADDRESS__)
#define KG_UNDER_ASAN 1
#endif

// Under AddressSanitizer from the heap, where an access past the block is
// caught.
#if (defined(__unix__) || defined(__APPLE__)) && !defined(KG_UNDER_ASAN)
#include <sys/mman.h>
#define KG_HAVE_ANONYMOUS_PAGES 1
#else
#define KG_HAVE_ANONYMOUS_PAGES 0
#endif

namespace kg {
namespace {
constexpr std::align_val_t kHeapAlignment{64};
}  // namespace

void* allocate_pages(std::size_t bytes) {
  if (bytes == 0) bytes = 1;
#if KG_HAVE_ANONYMOUS_PAGES
  void* block = ::mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  return block == MAP_FAILED ? nullptr : block;
#else
  return ::operator new(bytes, kHeapAlignment, std::nothrow);
#endif
}

void release_pages(void* block, std::size_t bytes) {
  if (block == nullptr) return;
#if KG_HAVE_ANONYMOUS_PAGES
  ::munmap(block, bytes == 0 ? 1 : bytes);
#else
  (void)bytes;
  ::operator delete(block, kHeapAlignment);
#endif
}

}  // namespace kg
