// Memory for the per-frame work of a Detector (DESIGN.md: no heap
// allocation after construction). Every buffer the core uses per frame is a
// WorkVector (std::pmr::vector) whose capacity is reserved once, when the
// Detector is built, from a Workspace: a bump allocator over one block of
// memory, the Detector's own or the caller's. Per frame, vectors are only
// cleared and refilled within their capacity (callers check it and degrade
// when it is reached), so the Workspace never hands out memory again; its
// used() figure staying put is what the tests check.
//
// Stage classes take a std::pmr::memory_resource; outside a Detector (tests,
// the desktop builder) the default resource is the heap and vectors grow as
// usual.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory_resource>
#include <vector>

namespace kg {

template <class T>
using WorkVector = std::pmr::vector<T>;

inline constexpr std::size_t kWorkspaceAlignment = 64;

inline std::size_t align_up(std::size_t v, std::size_t alignment) {
  return (v + alignment - 1) & ~(alignment - 1);
}

// Bump allocator over [base, base + size). Deallocation is a no-op: memory
// is reclaimed only with the whole block. Running out is a programming
// error, not a runtime condition (the Detector measures the layout with a
// MeasuringResource before it builds one), so it aborts: pmr allocators may
// not return null, and the core has no exceptions.
class Workspace final : public std::pmr::memory_resource {
 public:
  Workspace(void* base, std::size_t size) : base_(static_cast<std::uint8_t*>(base)), size_(size) {}
  std::size_t used() const { return used_; }
  std::size_t size() const { return size_; }

 private:
  void* do_allocate(std::size_t bytes, std::size_t alignment) override;
  void do_deallocate(void*, std::size_t, std::size_t) override {}
  bool do_is_equal(const std::pmr::memory_resource& other) const noexcept override {
    return this == &other;
  }

  std::uint8_t* base_;
  std::size_t size_;
  std::size_t used_ = 0;
};

// Counts what a Workspace starting at a kWorkspaceAlignment boundary would
// hand out for the same requests (alignment padding included), without
// memory: it returns a placeholder address that must never be dereferenced.
// Lays a workspace out by running the very reserve() calls that build it,
// with nothing written (WorkVector::reserve on an empty vector only stores
// the pointer; see Detector::workspace_bytes).
class MeasuringResource final : public std::pmr::memory_resource {
 public:
  std::size_t measured() const { return measured_; }

 private:
  void* do_allocate(std::size_t bytes, std::size_t alignment) override;
  void do_deallocate(void*, std::size_t, std::size_t) override {}
  bool do_is_equal(const std::pmr::memory_resource& other) const noexcept override {
    return this == &other;
  }

  std::size_t measured_ = 0;
};

}  // namespace kg
