// Owned 2-D pixel buffer used for the core's intermediate images. Its
// storage is reused across frames: resize() only allocates when the image
// grows beyond what it already holds, which in a Detector never happens
// (reserve() sized it for the largest frame once).
#pragma once

#include <cstddef>
#include <cstdint>

#include "core/support/workspace.h"
#include "keygraph/image.h"

namespace kg {

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
  WorkVector<T> pixels_;
  int width_ = 0;
  int height_ = 0;
};

inline ImageView view_of(const Plane<std::uint8_t>& p) {
  return ImageView(p.data(), p.width(), p.height(), p.width());
}

}  // namespace kg
