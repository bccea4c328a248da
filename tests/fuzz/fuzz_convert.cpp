// libFuzzer target for the camera frame conversions (platform/convert.h):
// the first 8 input bytes choose a layout (format, width, height, extra
// stride, and how short or long the buffer is), the rest are the pixels.
// Odd widths, padded strides and short buffers are the interesting cases:
// to_gray must reject a buffer shorter than luma_bytes() and otherwise read
// only within it (the buffer is exactly the given size, so AddressSanitizer
// sees any overread), and the scalar and the SIMD paths must agree.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "keygraph/simd.h"
#include "platform/convert.h"

namespace {

using kg::platform::FrameLayout;
using kg::platform::PixelFormat;

void require(bool ok, const char* what) {
  if (!ok) {
    std::fprintf(stderr, "fuzz_convert: %s\n", what);
    std::abort();
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 8) return 0;
  FrameLayout layout;
  layout.format = static_cast<PixelFormat>(data[0] % 5);
  layout.width = 1 + ((data[1] | (data[2] << 8)) % 700);  // up to 700: odd and even
  layout.height = 1 + ((data[3] | (data[4] << 8)) % 500);
  layout.stride = static_cast<std::ptrdiff_t>(
      kg::platform::min_stride(layout.format, layout.width) + data[5] % 70);
  if (data[6] & 0x80) layout.stride = data[5];  // sometimes too small a stride
  const std::uint8_t* pixels = data + 8;
  std::size_t available = size - 8;
  // The buffer the conversion sees: the input's bytes, exactly as many as
  // the frame needs (or the luma part), give or take data[7] % 16.
  const std::size_t luma = kg::platform::luma_bytes(layout);
  const int slack = static_cast<int>(data[7] % 16) - 8;
  std::size_t wanted = luma;
  if (slack < 0) wanted = luma > static_cast<std::size_t>(-slack) ? luma + slack : 0;
  if (slack > 0) wanted = luma + static_cast<std::size_t>(slack);
  if (wanted > available) wanted = available;
  std::vector<std::uint8_t> frame(pixels, pixels + wanted);
  frame.shrink_to_fit();

  const std::size_t scratch_size =
      static_cast<std::size_t>(layout.width) * static_cast<std::size_t>(layout.height);
  std::vector<std::uint8_t> scratch_a(scratch_size), scratch_b(scratch_size);
  kg::ImageView a, b;
  kg::set_simd_level(kg::best_simd_level());
  const kg::Status sa = kg::platform::to_gray(layout, frame.data(), frame.size(), scratch_a.data(),
                                              scratch_a.size(), a);
  kg::set_simd_level(kg::SimdLevel::kScalar);
  const kg::Status sb = kg::platform::to_gray(layout, frame.data(), frame.size(), scratch_b.data(),
                                              scratch_b.size(), b);
  kg::set_simd_level(kg::best_simd_level());
  require(sa.is_ok() == sb.is_ok(), "SIMD and scalar paths disagree on the status");
  if (luma == 0 || frame.size() < luma)
    require(!sa.is_ok(), "accepted a short buffer or bad layout");
  if (!sa.is_ok()) return 0;
  require(a.width == layout.width && a.height == layout.height, "wrong output size");
  std::vector<std::uint8_t> copy_a(scratch_size), copy_b(scratch_size);
  kg::platform::copy_gray(a, copy_a.data(), layout.width);
  kg::platform::copy_gray(b, copy_b.data(), layout.width);
  require(copy_a == copy_b, "SIMD and scalar paths give different pixels");
  return 0;
}
