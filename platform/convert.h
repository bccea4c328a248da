// Camera pixel formats to 8-bit gray.
//
// Formats whose first plane is luma (GREY, NV12, YU12) become a view of that
// plane: no pixel is copied, whatever the stride. Packed 4:2:2 formats (YUYV,
// UYVY) are converted into a caller-provided buffer. The packed conversions
// have a NEON path, compiled when the target has NEON (__ARM_NEON) and
// KG_PLATFORM_NO_NEON is not defined, and a scalar path that is always
// compiled; simd_level() (keygraph/simd.h) chooses, as for the core's
// loops, and both give identical bytes (tested).
//
// Layout conventions (those of V4L2 single-planar formats):
// - `stride` is the number of bytes from one row of the first plane to the
//   next (V4L2 bytesperline); it may exceed the row's payload (padding).
// - NV12: a luma plane of stride * height bytes, then one interleaved CbCr
//   plane of ceil(height / 2) rows with the same stride.
// - YU12 (I420, V4L2 YUV420): a luma plane of stride * height bytes, then Cb
//   and Cr planes of ceil(height / 2) rows each with stride ceil(stride / 2).
// - YUYV / UYVY: one plane, 2 bytes per pixel; a row holds ceil(width / 2)
//   4-byte macropixels (Y0 U Y1 V / U Y0 V Y1), so odd widths are allowed.
#pragma once

#include <cstddef>
#include <cstdint>

#include "keygraph/image.h"
#include "keygraph/status.h"

namespace kg::platform {

enum class PixelFormat : std::uint8_t { kGrey, kNv12, kYu12, kYuyv, kUyvy };

// "GREY", "NV12", "YU12", "YUYV", "UYVY".
const char* pixel_format_name(PixelFormat format);

// True when the gray image is a view of the frame's first plane (no copy).
bool is_zero_copy(PixelFormat format);

struct FrameLayout {
  PixelFormat format = PixelFormat::kGrey;
  int width = 0;              // pixels
  int height = 0;             // rows
  std::ptrdiff_t stride = 0;  // bytes per row of the first plane
};

// Bytes of payload in one row of the first plane: width for GREY/NV12/YU12,
// 4 * ceil(width / 2) for YUYV/UYVY.
std::size_t min_stride(PixelFormat format, int width);

// Checks that the layout is usable: positive size, stride >= min_stride,
// frame size representable. One clear message on failure (kInvalidArgument).
Status check_layout(const FrameLayout& layout);

// Bytes of a whole frame with all its planes stored one after the other, as
// V4L2 single-planar buffers hold them (see the layout conventions above).
// 0 when check_layout fails.
std::size_t frame_bytes(const FrameLayout& layout);

// Bytes the gray conversion reads from the start of the buffer: the first
// plane up to the end of its last row's payload. 0 when check_layout fails.
std::size_t luma_bytes(const FrameLayout& layout);

// True when this build has a NEON path for the packed conversions.
bool neon_compiled();

// Gray view of one frame held in `data` (`size` bytes available).
// Zero-copy formats: `out` views `data` with the layout's stride and
// `scratch` is not touched (it may be null). Packed formats: the luma bytes
// are written to `scratch`, rows `width` bytes apart, and `out` views it;
// scratch_size must be at least width * height.
// Errors: invalid layout (kInvalidArgument); size < luma_bytes(layout):
// "short buffer" (kCorruptData); scratch missing or too small
// (kInvalidArgument). `out` is left unchanged on error.
Status to_gray(const FrameLayout& layout, const std::uint8_t* data, std::size_t size,
               std::uint8_t* scratch, std::size_t scratch_size, ImageView& out);

// Packed 4:2:2 to gray: dst(x, y) = the Y byte of pixel (x, y). The caller
// guarantees the layout (src rows of at least min_stride bytes, dst rows of
// at least width bytes); width, height > 0.
void yuyv_to_gray(const std::uint8_t* src, std::ptrdiff_t src_stride, int width, int height,
                  std::uint8_t* dst, std::ptrdiff_t dst_stride);
void uyvy_to_gray(const std::uint8_t* src, std::ptrdiff_t src_stride, int width, int height,
                  std::uint8_t* dst, std::ptrdiff_t dst_stride);

// Copies a gray view into dst (rows dst_stride >= width bytes apart), for
// callers that keep a frame past the next call to FrameSource::next().
void copy_gray(const ImageView& src, std::uint8_t* dst, std::ptrdiff_t dst_stride);

}  // namespace kg::platform
