// Owned 2-D pixel buffer used for the core's intermediate images. Its
// storage is reused across frames: resize() only allocates when the image
// grows beyond what it already holds, which in a Detector never happens
// (reserve() sized it for the largest frame once).
#pragma once

#include <cstddef>
#include <cstdint>
#include <new>
#include <type_traits>
#include <utility>
#include <vector>

#include "core/support/workspace.h"
#include "keygraph/image.h"

namespace kg {

// The workspace's allocator, but growing a vector default-initialises its
// new elements instead of value-initialising them: for pixels, nothing is
// written. Every plane's pixels are written before they are read, and
// zeroing a 1280x720 frame's planes on the first frame cost ~10 M
// instructions (the workspace's pages are fresh, zero, anyway).
template <class T>
struct UnwrittenAllocator : std::pmr::polymorphic_allocator<T> {
  using std::pmr::polymorphic_allocator<T>::polymorphic_allocator;
  UnwrittenAllocator() = default;
  UnwrittenAllocator(const std::pmr::polymorphic_allocator<T>& a) noexcept  // NOLINT: as pmr's
      : std::pmr::polymorphic_allocator<T>(a) {}
  // A copied plane uses the default resource, as a copied WorkVector does.
  UnwrittenAllocator select_on_container_copy_construction() const { return {}; }
  template <class U>
  struct rebind {
    using other = UnwrittenAllocator<U>;
  };
  template <class U>
  void construct(U* p) noexcept(std::is_nothrow_default_constructible_v<U>) {
    ::new (static_cast<void*>(p)) U;
  }
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    std::pmr::polymorphic_allocator<T>::construct(p, std::forward<Args>(args)...);
  }
};

template <class T>
class Plane {
 public:
  explicit Plane(std::pmr::memory_resource* memory = std::pmr::get_default_resource())
      : pixels_(memory) {}
  void reserve(int width, int height) {
    pixels_.reserve(static_cast<std::size_t>(width) * static_cast<std::size_t>(height));
  }
  void resize(int width, int height) {
    width_ = width;
    height_ = height;
    const std::size_t n = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
    if (pixels_.size() < n) pixels_.resize(n);
  }
  int width() const { return width_; }
  int height() const { return height_; }
  T* row(int y) { return pixels_.data() + static_cast<std::size_t>(y) * width_; }
  const T* row(int y) const { return pixels_.data() + static_cast<std::size_t>(y) * width_; }
  T& at(int x, int y) { return row(y)[x]; }
  const T& at(int x, int y) const { return row(y)[x]; }
  T* data() { return pixels_.data(); }
  const T* data() const { return pixels_.data(); }
  std::size_t capacity_bytes() const { return pixels_.capacity() * sizeof(T); }

 private:
  std::vector<T, UnwrittenAllocator<T>> pixels_;
  int width_ = 0;
  int height_ = 0;
};

inline ImageView view_of(const Plane<std::uint8_t>& p) {
  return ImageView(p.data(), p.width(), p.height(), p.width());
}

}  // namespace kg
