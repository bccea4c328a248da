// Non-owning view of an 8-bit grayscale image.
//
// Conventions used everywhere in keygraph: pixel (x, y) is column x, row y;
// the centre of the top-left pixel is (0, 0); y grows downwards. A camera
// buffer or a cv::Mat is wrapped without a copy; the caller owns the memory
// and keeps it alive while the view is used.
#pragma once

#include <cstddef>
#include <cstdint>

namespace kg {

struct ImageView {
  const std::uint8_t* data = nullptr;
  int width = 0;
  int height = 0;
  std::ptrdiff_t stride = 0;  // bytes from one row to the next, >= width

  ImageView() = default;
  ImageView(const std::uint8_t* d, int w, int h, std::ptrdiff_t s)
      : data(d), width(w), height(h), stride(s) {}
  ImageView(const std::uint8_t* d, int w, int h) : ImageView(d, w, h, w) {}

  bool empty() const { return data == nullptr || width <= 0 || height <= 0; }
  const std::uint8_t* row(int y) const { return data + static_cast<std::ptrdiff_t>(y) * stride; }
  std::uint8_t at(int x, int y) const { return row(y)[x]; }
};

}  // namespace kg
