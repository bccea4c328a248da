// Pixel-format conversions against known buffers: every format, odd widths,
// padded (also odd) strides, short buffers, and the NEON path against the
// scalar one where the build has NEON.
#include <cstdint>
#include <cstdio>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "platform/convert.h"
#include "support/simd_scope.h"

namespace kg::platform {
namespace {

constexpr std::uint8_t kPad = 0xEE;  // padding bytes: must never reach the output

std::uint8_t luma(int x, int y) {
  return static_cast<std::uint8_t>((x * 7 + y * 31 + 3) & 0xff);
}
std::uint8_t chroma(int x, int y, int c) {
  return static_cast<std::uint8_t>(((x * 13 + y * 5) ^ (c ? 0x5a : 0xa5)) & 0xff);
}

// A packed 4:2:2 frame holding luma(x, y): YUYV when uyvy is false.
std::vector<std::uint8_t> make_packed(int w, int h, std::ptrdiff_t stride, bool uyvy) {
  std::vector<std::uint8_t> buf(static_cast<std::size_t>(stride * h), kPad);
  for (int y = 0; y < h; ++y) {
    std::uint8_t* row = buf.data() + y * stride;
    for (int m = 0; m < (w + 1) / 2; ++m) {
      const std::uint8_t y0 = luma(2 * m, y);
      const std::uint8_t y1 = 2 * m + 1 < w ? luma(2 * m + 1, y) : 0x77;  // odd width: unused Y1
      const std::uint8_t u = chroma(m, y, 0), v = chroma(m, y, 1);
      const std::uint8_t yuyv[4] = {y0, u, y1, v};
      const std::uint8_t uyvy_bytes[4] = {u, y0, v, y1};
      for (int i = 0; i < 4; ++i) row[4 * m + i] = uyvy ? uyvy_bytes[i] : yuyv[i];
    }
  }
  return buf;
}

// A planar 4:2:0 frame (NV12 or YU12) laid out as convert.h describes.
std::vector<std::uint8_t> make_planar(const FrameLayout& l) {
  std::vector<std::uint8_t> buf(frame_bytes(l), kPad);
  for (int y = 0; y < l.height; ++y) {
    for (int x = 0; x < l.width; ++x) buf[y * l.stride + x] = luma(x, y);
  }
  for (std::size_t i = static_cast<std::size_t>(l.stride * l.height); i < buf.size(); ++i) {
    buf[i] = static_cast<std::uint8_t>(i * 11);
  }
  return buf;
}

void expect_luma(const ImageView& v, int w, int h) {
  ASSERT_EQ(v.width, w);
  ASSERT_EQ(v.height, h);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      ASSERT_EQ(v.at(x, y), luma(x, y)) << "pixel (" << x << ", " << y << ") of " << w << "x" << h;
    }
  }
}

TEST(Convert, NamesAndZeroCopyFormats) {
  EXPECT_STREQ(pixel_format_name(PixelFormat::kGrey), "GREY");
  EXPECT_STREQ(pixel_format_name(PixelFormat::kNv12), "NV12");
  EXPECT_STREQ(pixel_format_name(PixelFormat::kYu12), "YU12");
  EXPECT_STREQ(pixel_format_name(PixelFormat::kYuyv), "YUYV");
  EXPECT_STREQ(pixel_format_name(PixelFormat::kUyvy), "UYVY");
  EXPECT_TRUE(is_zero_copy(PixelFormat::kGrey));
  EXPECT_TRUE(is_zero_copy(PixelFormat::kNv12));
  EXPECT_TRUE(is_zero_copy(PixelFormat::kYu12));
  EXPECT_FALSE(is_zero_copy(PixelFormat::kYuyv));
  EXPECT_FALSE(is_zero_copy(PixelFormat::kUyvy));
}

TEST(Convert, FrameSizes) {
  EXPECT_EQ(frame_bytes({PixelFormat::kGrey, 640, 480, 640}), 640u * 480u);
  EXPECT_EQ(frame_bytes({PixelFormat::kNv12, 640, 480, 640}), 640u * 480u * 3u / 2u);
  EXPECT_EQ(frame_bytes({PixelFormat::kYu12, 640, 480, 640}), 640u * 480u * 3u / 2u);
  EXPECT_EQ(frame_bytes({PixelFormat::kYuyv, 640, 480, 1280}), 640u * 480u * 2u);
  // Odd sizes: chroma rows round up, YU12 chroma stride is ceil(stride / 2).
  EXPECT_EQ(frame_bytes({PixelFormat::kNv12, 5, 3, 6}), 6u * 3u + 6u * 2u);
  EXPECT_EQ(frame_bytes({PixelFormat::kYu12, 5, 3, 7}), 7u * 3u + 2u * 4u * 2u);
  // A YUYV row of odd width still holds whole macropixels.
  EXPECT_EQ(min_stride(PixelFormat::kYuyv, 5), 12u);
  EXPECT_EQ(min_stride(PixelFormat::kUyvy, 4), 8u);
  EXPECT_EQ(min_stride(PixelFormat::kNv12, 5), 5u);
  // The luma bytes end with the last row's payload, not its padding.
  EXPECT_EQ(luma_bytes({PixelFormat::kNv12, 5, 3, 8}), 8u * 2u + 5u);
  EXPECT_EQ(luma_bytes({PixelFormat::kYuyv, 3, 2, 16}), 16u + 8u);
}

TEST(Convert, RejectsBadLayouts) {
  const FrameLayout bad[] = {
      {PixelFormat::kGrey, 0, 10, 10},           {PixelFormat::kGrey, 10, -1, 10},
      {PixelFormat::kGrey, 10, 10, 9},           {PixelFormat::kYuyv, 5, 2, 10},  // needs 12
      {PixelFormat::kNv12, 40000, 10, 40000},    {PixelFormat::kGrey, 10, 10, -10},
      {PixelFormat::kNv12, 32000, 32000, 32000},  // over 1 GiB
  };
  for (const FrameLayout& l : bad) {
    const Status s = check_layout(l);
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument) << l.width << "x" << l.height;
    EXPECT_NE(s.message().find("frame layout"), std::string::npos) << s.message();
    EXPECT_EQ(frame_bytes(l), 0u);
    EXPECT_EQ(luma_bytes(l), 0u);
    ImageView out;
    std::vector<std::uint8_t> data(64), scratch(64);
    EXPECT_EQ(to_gray(l, data.data(), data.size(), scratch.data(), scratch.size(), out).code(),
              StatusCode::kInvalidArgument);
    EXPECT_TRUE(out.empty());
  }
}

// GREY, NV12 and YU12 give a view of the luma plane: same pointer, same
// stride, whatever the padding.
TEST(Convert, LumaPlaneFormatsAreViewsWithoutCopy) {
  for (PixelFormat f : {PixelFormat::kGrey, PixelFormat::kNv12, PixelFormat::kYu12}) {
    for (int w : {1, 3, 16, 17, 33}) {
      for (int h : {1, 2, 5}) {
        for (int pad : {0, 1, 7, 64}) {
          const FrameLayout l{f, w, h, w + pad};
          const std::vector<std::uint8_t> buf = make_planar(l);
          ImageView out;
          ASSERT_TRUE(to_gray(l, buf.data(), buf.size(), nullptr, 0, out))
              << pixel_format_name(f) << " " << w << "x" << h;
          EXPECT_EQ(out.data, buf.data());
          EXPECT_EQ(out.stride, l.stride);
          expect_luma(out, w, h);
        }
      }
    }
  }
}

TEST(Convert, YuyvKnownBuffer) {
  // 3x2, stride 16: two macropixels per row (the second one's Y1 unused),
  // then 8 padding bytes.
  const std::uint8_t p = kPad;
  const std::uint8_t frame[32] = {
      10, 128, 11, 129, 12, 130, 99, 131, p, p, p, p, p, p, p, p,
      20, 140, 21, 141, 22, 142, 98, 143, p, p, p, p, p, p, p, p,
  };
  for (SimdLevel level : {best_simd_level(), SimdLevel::kScalar}) {
    const test::SimdScope scope(level);
    std::uint8_t gray[6] = {};
    ImageView out;
    ASSERT_TRUE(
        to_gray({PixelFormat::kYuyv, 3, 2, 16}, frame, sizeof frame, gray, sizeof gray, out));
    EXPECT_EQ(out.data, gray);
    EXPECT_EQ(out.stride, 3);
    const std::uint8_t expected[6] = {10, 11, 12, 20, 21, 22};
    for (int i = 0; i < 6; ++i) EXPECT_EQ(gray[i], expected[i]) << i;
  }
}

TEST(Convert, UyvyKnownBuffer) {
  const std::uint8_t frame[16] = {
      128, 10, 129, 11, 130, 12, 131, 13,  // row 0: 4 pixels
      140, 20, 141, 21, 142, 22, 143, 23,  // row 1
  };
  for (SimdLevel level : {best_simd_level(), SimdLevel::kScalar}) {
    const test::SimdScope scope(level);
    std::uint8_t gray[8] = {};
    ImageView out;
    ASSERT_TRUE(
        to_gray({PixelFormat::kUyvy, 4, 2, 8}, frame, sizeof frame, gray, sizeof gray, out));
    const std::uint8_t expected[8] = {10, 11, 12, 13, 20, 21, 22, 23};
    for (int i = 0; i < 8; ++i) EXPECT_EQ(gray[i], expected[i]) << i;
  }
}

// Widths around the NEON block sizes (16 and 32 pixels), odd strides.
TEST(Convert, PackedOddWidthsAndPaddedStrides) {
  for (bool uyvy : {false, true}) {
    const PixelFormat f = uyvy ? PixelFormat::kUyvy : PixelFormat::kYuyv;
    for (int w : {1, 2, 3, 15, 16, 17, 31, 32, 33, 47, 63, 64, 65, 641}) {
      for (int h : {1, 2, 7}) {
        for (int pad : {0, 1, 5, 64}) {
          const std::ptrdiff_t stride = static_cast<std::ptrdiff_t>(min_stride(f, w)) + pad;
          const std::vector<std::uint8_t> buf = make_packed(w, h, stride, uyvy);
          for (SimdLevel level : {best_simd_level(), SimdLevel::kScalar}) {
            const test::SimdScope scope(level);
            std::vector<std::uint8_t> gray(static_cast<std::size_t>(w * h));
            ImageView out;
            // Exactly the bytes read: the last row without its padding.
            const std::size_t size = luma_bytes({f, w, h, stride});
            ASSERT_LE(size, buf.size());
            ASSERT_TRUE(
                to_gray({f, w, h, stride}, buf.data(), size, gray.data(), gray.size(), out));
            expect_luma(out, w, h);
          }
        }
      }
    }
  }
}

// The kernels write exactly width bytes per destination row.
TEST(Convert, PackedKernelsLeaveDestinationPaddingAlone) {
  const int w = 37, h = 3;
  const std::ptrdiff_t src_stride = 80, dst_stride = 45;
  for (bool uyvy : {false, true}) {
    const std::vector<std::uint8_t> src = make_packed(w, h, src_stride, uyvy);
    for (SimdLevel level : {best_simd_level(), SimdLevel::kScalar}) {
      const test::SimdScope scope(level);
      std::vector<std::uint8_t> dst(static_cast<std::size_t>(dst_stride * h), 0xCD);
      if (uyvy) {
        uyvy_to_gray(src.data(), src_stride, w, h, dst.data(), dst_stride);
      } else {
        yuyv_to_gray(src.data(), src_stride, w, h, dst.data(), dst_stride);
      }
      expect_luma(ImageView(dst.data(), w, h, dst_stride), w, h);
      for (int y = 0; y < h; ++y) {
        for (int x = w; x < dst_stride; ++x) EXPECT_EQ(dst[y * dst_stride + x], 0xCD) << x;
      }
    }
  }
}

// NEON (kAuto on ARM) and scalar give identical bytes on random frames. On a
// build without NEON both calls take the scalar path and this still checks
// the dispatch.
TEST(Convert, NeonMatchesScalarOnRandomFrames) {
  std::mt19937 rng(12345);
  std::uniform_int_distribution<int> byte(0, 255), width(1, 700), height(1, 9), pad(0, 40);
  for (int trial = 0; trial < 200; ++trial) {
    const int w = width(rng), h = height(rng);
    const bool uyvy = trial % 2 == 1;
    const PixelFormat f = uyvy ? PixelFormat::kUyvy : PixelFormat::kYuyv;
    const std::ptrdiff_t stride = static_cast<std::ptrdiff_t>(min_stride(f, w)) + pad(rng);
    std::vector<std::uint8_t> src(static_cast<std::size_t>(stride * h));
    for (std::uint8_t& b : src) b = static_cast<std::uint8_t>(byte(rng));
    std::vector<std::uint8_t> a(static_cast<std::size_t>(w * h)), s(a.size());
    ImageView va, vs;
    ASSERT_TRUE(to_gray({f, w, h, stride}, src.data(), src.size(), a.data(), a.size(), va));
    ASSERT_TRUE([&] {
      const test::SimdScope scalar(SimdLevel::kScalar);
      return to_gray({f, w, h, stride}, src.data(), src.size(), s.data(), s.size(), vs);
    }());
    ASSERT_EQ(a, s) << pixel_format_name(f) << " " << w << "x" << h << " stride " << stride;
    // And both equal the definition: every other byte.
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        ASSERT_EQ(s[y * w + x], src[y * stride + 2 * x + (uyvy ? 1 : 0)]);
      }
    }
  }
}

TEST(Convert, NeonIsCompiledWhereTheTargetHasIt) {
#if defined(__ARM_NEON) && !defined(KG_PLATFORM_NO_NEON)
  EXPECT_TRUE(neon_compiled());
#else
  EXPECT_FALSE(neon_compiled());
#endif
  std::printf("packed conversions: %s path\n", neon_compiled() ? "NEON" : "scalar");
}

TEST(Convert, ShortBufferIsOneClearError) {
  for (PixelFormat f : {PixelFormat::kGrey, PixelFormat::kNv12, PixelFormat::kYu12,
                        PixelFormat::kYuyv, PixelFormat::kUyvy}) {
    const FrameLayout l{f, 33, 5, static_cast<std::ptrdiff_t>(min_stride(f, 33)) + 3};
    const std::size_t need = luma_bytes(l);
    std::vector<std::uint8_t> buf(need, 1), scratch(33 * 5);
    ImageView out;
    const Status s = to_gray(l, buf.data(), need - 1, scratch.data(), scratch.size(), out);
    EXPECT_EQ(s.code(), StatusCode::kCorruptData) << pixel_format_name(f);
    EXPECT_NE(s.message().find("short buffer"), std::string::npos) << s.message();
    EXPECT_NE(s.message().find(std::to_string(need)), std::string::npos) << s.message();
    EXPECT_TRUE(out.empty());
    EXPECT_EQ(to_gray(l, nullptr, need, scratch.data(), scratch.size(), out).code(),
              StatusCode::kCorruptData);
    EXPECT_TRUE(to_gray(l, buf.data(), need, scratch.data(), scratch.size(), out));
  }
}

TEST(Convert, PackedNeedsLargeEnoughScratch) {
  const FrameLayout l{PixelFormat::kYuyv, 8, 4, 16};
  std::vector<std::uint8_t> buf(frame_bytes(l), 0), scratch(8 * 4 - 1);
  ImageView out;
  Status s = to_gray(l, buf.data(), buf.size(), scratch.data(), scratch.size(), out);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("too small"), std::string::npos) << s.message();
  s = to_gray(l, buf.data(), buf.size(), nullptr, 0, out);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_TRUE(out.empty());
}

TEST(Convert, CopyGrayRepacksRows) {
  const FrameLayout l{PixelFormat::kNv12, 5, 3, 9};
  const std::vector<std::uint8_t> buf = make_planar(l);
  ImageView view;
  ASSERT_TRUE(to_gray(l, buf.data(), buf.size(), nullptr, 0, view));
  std::vector<std::uint8_t> copy(5 * 3);
  copy_gray(view, copy.data(), 5);
  expect_luma(ImageView(copy.data(), 5, 3), 5, 3);
}

}  // namespace
}  // namespace kg::platform
