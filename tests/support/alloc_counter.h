// Counts heap allocations made through operator new, for tests asserting
// that a call allocates nothing. Include from exactly one source file of a
// test program: it replaces every global operator new and delete (plain,
// array, nothrow, sized and aligned), all on malloc/free so that sanitizers
// see matching pairs.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdlib>
#include <new>

namespace kg::test {

inline std::atomic<long> g_heap_allocations{0};

// Allocations since construction.
class AllocationCounter {
 public:
  AllocationCounter() : start_(g_heap_allocations.load()) {}
  long count() const { return g_heap_allocations.load() - start_; }

 private:
  long start_;
};

inline void* counted_alloc(std::size_t n) {
  ++g_heap_allocations;
  return std::malloc(n == 0 ? 1 : n);
}

inline void* counted_aligned_alloc(std::size_t n, std::align_val_t align) {
  ++g_heap_allocations;
  const auto a = static_cast<std::size_t>(align) < sizeof(void*) ? sizeof(void*)
                                                                 : static_cast<std::size_t>(align);
  void* p = nullptr;
  return ::posix_memalign(&p, a, n == 0 ? 1 : n) == 0 ? p : nullptr;
}

}  // namespace kg::test

// These free() what the replacements below malloc()ed; GCC cannot tell.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
#endif

void* operator new(std::size_t n) {
  if (void* p = kg::test::counted_alloc(n)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t n) {
  if (void* p = kg::test::counted_alloc(n)) return p;
  throw std::bad_alloc();
}
void* operator new(std::size_t n, const std::nothrow_t&) noexcept {
  return kg::test::counted_alloc(n);
}
void* operator new[](std::size_t n, const std::nothrow_t&) noexcept {
  return kg::test::counted_alloc(n);
}
void* operator new(std::size_t n, std::align_val_t a) {
  if (void* p = kg::test::counted_aligned_alloc(n, a)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t n, std::align_val_t a) {
  if (void* p = kg::test::counted_aligned_alloc(n, a)) return p;
  throw std::bad_alloc();
}
void* operator new(std::size_t n, std::align_val_t a, const std::nothrow_t&) noexcept {
  return kg::test::counted_aligned_alloc(n, a);
}
void* operator new[](std::size_t n, std::align_val_t a, const std::nothrow_t&) noexcept {
  return kg::test::counted_aligned_alloc(n, a);
}
void operator delete(void* p) noexcept {
  std::free(p);
}
void operator delete[](void* p) noexcept {
  std::free(p);
}
void operator delete(void* p, std::size_t) noexcept {
  std::free(p);
}
void operator delete[](void* p, std::size_t) noexcept {
  std::free(p);
}
void operator delete(void* p, const std::nothrow_t&) noexcept {
  std::free(p);
}
void operator delete[](void* p, const std::nothrow_t&) noexcept {
  std::free(p);
}
void operator delete(void* p, std::align_val_t) noexcept {
  std::free(p);
}
void operator delete[](void* p, std::align_val_t) noexcept {
  std::free(p);
}
void operator delete(void* p, std::size_t, std::align_val_t) noexcept {
  std::free(p);
}
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept {
  std::free(p);
}
void operator delete(void* p, std::align_val_t, const std::nothrow_t&) noexcept {
  std::free(p);
}
void operator delete[](void* p, std::align_val_t, const std::nothrow_t&) noexcept {
  std::free(p);
}

#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic pop
#endif
