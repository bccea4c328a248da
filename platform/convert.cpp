#include "platform/convert.h"

#include <cstdint>
#include <cstring>
#include <limits>
#include <string>

#include "keygraph/simd.h"

#if defined(__ARM_NEON) && !defined(KG_PLATFORM_NO_NEON)
#include <arm_neon.h>
#define KG_PLATFORM_HAVE_NEON 1
#else
#define KG_PLATFORM_HAVE_NEON 0
#endif

namespace kg::platform {
namespace {

// Frames larger than this are rejected as implausible (and keep every size
// computation far from overflow, also with a 32-bit size_t).
constexpr int kMaxDimension = 1 << 15;  // 32768
constexpr std::uint64_t kMaxFrameBytes = std::uint64_t{1} << 30;

// Y bytes sit at offset `first` of every 2-byte pixel: 0 for YUYV, 1 for UYVY.
void packed_scalar(const std::uint8_t* src, std::ptrdiff_t src_stride, int width, int height,
                   std::uint8_t* dst, std::ptrdiff_t dst_stride, int first) {
  for (int y = 0; y < height; ++y) {
    const std::uint8_t* s = src + static_cast<std::ptrdiff_t>(y) * src_stride + first;
    std::uint8_t* d = dst + static_cast<std::ptrdiff_t>(y) * dst_stride;
    for (int x = 0; x < width; ++x) d[x] = s[2 * x];
  }
}

#if KG_PLATFORM_HAVE_NEON
// vld2q splits 32 bytes into even and odd bytes: 16 Y bytes per load. Two
// loads per iteration, then the scalar loop for the last < 32 pixels. Reads
// stay within the row's 2 * width bytes.
template <int kFirst>
void packed_neon(const std::uint8_t* src, std::ptrdiff_t src_stride, int width, int height,
                 std::uint8_t* dst, std::ptrdiff_t dst_stride) {
  for (int y = 0; y < height; ++y) {
    const std::uint8_t* s = src + static_cast<std::ptrdiff_t>(y) * src_stride;
    std::uint8_t* d = dst + static_cast<std::ptrdiff_t>(y) * dst_stride;
    int x = 0;
    for (; x + 32 <= width; x += 32) {
      const uint8x16x2_t a = vld2q_u8(s + 2 * x);
      const uint8x16x2_t b = vld2q_u8(s + 2 * x + 32);
      vst1q_u8(d + x, a.val[kFirst]);
      vst1q_u8(d + x + 16, b.val[kFirst]);
    }
    for (; x + 16 <= width; x += 16) vst1q_u8(d + x, vld2q_u8(s + 2 * x).val[kFirst]);
    for (; x < width; ++x) d[x] = s[2 * x + kFirst];
  }
}
#endif

std::uint64_t frame_bytes_u64(const FrameLayout& l) {
  const std::uint64_t stride = static_cast<std::uint64_t>(l.stride);
  const std::uint64_t h = static_cast<std::uint64_t>(l.height);
  const std::uint64_t chroma_rows = (h + 1) / 2;
  switch (l.format) {
    case PixelFormat::kGrey:
    case PixelFormat::kYuyv:
    case PixelFormat::kUyvy:
      return stride * h;
    case PixelFormat::kNv12:
      return stride * h + stride * chroma_rows;
    case PixelFormat::kYu12:
      return stride * h + 2 * ((stride + 1) / 2) * chroma_rows;
  }
  return 0;
}

}  // namespace

const char* pixel_format_name(PixelFormat format) {
  switch (format) {
    case PixelFormat::kGrey:
      return "GREY";
    case PixelFormat::kNv12:
      return "NV12";
    case PixelFormat::kYu12:
      return "YU12";
    case PixelFormat::kYuyv:
      return "YUYV";
    case PixelFormat::kUyvy:
      return "UYVY";
  }
  return "unknown";
}

bool is_zero_copy(PixelFormat format) {
  return format == PixelFormat::kGrey || format == PixelFormat::kNv12 ||
         format == PixelFormat::kYu12;
}

std::size_t min_stride(PixelFormat format, int width) {
  if (width <= 0) return 0;
  const std::size_t w = static_cast<std::size_t>(width);
  return is_zero_copy(format) ? w : 4 * ((w + 1) / 2);
}

Status check_layout(const FrameLayout& l) {
  // Called per frame: builds a message (allocates) only on failure.
  const char* problem = nullptr;
  if (l.width <= 0 || l.height <= 0 || l.width > kMaxDimension || l.height > kMaxDimension) {
    problem = "width and height must be in 1..32768";
  } else if (l.stride < 0 || static_cast<std::size_t>(l.stride) < min_stride(l.format, l.width)) {
    problem = "stride below the bytes a row needs";
  } else if (static_cast<std::uint64_t>(l.stride) > kMaxFrameBytes ||
             frame_bytes_u64(l) > kMaxFrameBytes) {
    problem = "frame larger than 1 GiB";
  }
  if (problem == nullptr) return Status::ok();
  return {StatusCode::kInvalidArgument,
          std::string("frame layout ") + pixel_format_name(l.format) + " " +
              std::to_string(l.width) + "x" + std::to_string(l.height) + " stride " +
              std::to_string(l.stride) + ": " + problem + " (row needs " +
              std::to_string(min_stride(l.format, l.width)) + " bytes)"};
}

std::size_t frame_bytes(const FrameLayout& layout) {
  if (!check_layout(layout)) return 0;
  return static_cast<std::size_t>(frame_bytes_u64(layout));
}

std::size_t luma_bytes(const FrameLayout& layout) {
  if (!check_layout(layout)) return 0;
  return static_cast<std::size_t>(layout.stride) * static_cast<std::size_t>(layout.height - 1) +
         min_stride(layout.format, layout.width);
}

bool neon_compiled() {
  return KG_PLATFORM_HAVE_NEON != 0;
}

void yuyv_to_gray(const std::uint8_t* src, std::ptrdiff_t src_stride, int width, int height,
                  std::uint8_t* dst, std::ptrdiff_t dst_stride) {
#if KG_PLATFORM_HAVE_NEON
  if (simd_level() != SimdLevel::kScalar) {
    packed_neon<0>(src, src_stride, width, height, dst, dst_stride);
    return;
  }
#endif
  packed_scalar(src, src_stride, width, height, dst, dst_stride, 0);
}

void uyvy_to_gray(const std::uint8_t* src, std::ptrdiff_t src_stride, int width, int height,
                  std::uint8_t* dst, std::ptrdiff_t dst_stride) {
#if KG_PLATFORM_HAVE_NEON
  if (simd_level() != SimdLevel::kScalar) {
    packed_neon<1>(src, src_stride, width, height, dst, dst_stride);
    return;
  }
#endif
  packed_scalar(src, src_stride, width, height, dst, dst_stride, 1);
}

Status to_gray(const FrameLayout& layout, const std::uint8_t* data, std::size_t size,
               std::uint8_t* scratch, std::size_t scratch_size, ImageView& out) {
  if (Status s = check_layout(layout); !s) return s;
  const std::size_t needed = luma_bytes(layout);
  if (data == nullptr || size < needed) {
    return {StatusCode::kCorruptData,
            std::string("short buffer: ") + std::to_string(data == nullptr ? 0 : size) + " of " +
                std::to_string(needed) + " bytes for " + pixel_format_name(layout.format) + " " +
                std::to_string(layout.width) + "x" + std::to_string(layout.height)};
  }
  if (is_zero_copy(layout.format)) {
    out = ImageView(data, layout.width, layout.height, layout.stride);
    return Status::ok();
  }
  const std::size_t pixels =
      static_cast<std::size_t>(layout.width) * static_cast<std::size_t>(layout.height);
  if (scratch == nullptr || scratch_size < pixels) {
    return {StatusCode::kInvalidArgument,
            std::string("conversion buffer of ") + std::to_string(scratch_size) +
                " bytes is too small for " + pixel_format_name(layout.format) + " " +
                std::to_string(layout.width) + "x" + std::to_string(layout.height) + " (needs " +
                std::to_string(pixels) + ")"};
  }
  if (layout.format == PixelFormat::kYuyv) {
    yuyv_to_gray(data, layout.stride, layout.width, layout.height, scratch, layout.width);
  } else {
    uyvy_to_gray(data, layout.stride, layout.width, layout.height, scratch, layout.width);
  }
  out = ImageView(scratch, layout.width, layout.height, layout.width);
  return Status::ok();
}

void copy_gray(const ImageView& src, std::uint8_t* dst, std::ptrdiff_t dst_stride) {
  if (src.empty()) return;
  for (int y = 0; y < src.height; ++y) {
    std::memcpy(dst + static_cast<std::ptrdiff_t>(y) * dst_stride, src.row(y),
                static_cast<std::size_t>(src.width));
  }
}

}  // namespace kg::platform
