// The image size a header declares (platform/files/image_header.h), read
// before decoding so the pixel limit holds in every process: the same size
// OpenCV decodes, for every opencv-doc image and for each format written by
// OpenCV from a real photo; bombs refused (also at the reduced sizes of
// JPEG's reduced decoding); formats whose size is not read refused; broken
// headers left to the decoder.
#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "platform/files/image_header.h"
#include "platform/files/image_limits.h"

namespace kg::platform {
namespace {

using Bytes = std::vector<std::uint8_t>;

DeclaredSize of(const Bytes& b) {
  return declared_image_size(b.data(), b.size());
}

Bytes encode(const cv::Mat& image, const std::string& ext) {
  Bytes out;
  EXPECT_TRUE(cv::imencode(ext, image, out)) << ext;
  return out;
}

TEST(ImageHeader, EveryOpencvDocImageDeclaresTheSizeOpenCvDecodes) {
  int checked = 0;
  for (const auto& entry : std::filesystem::directory_iterator(KG_OPENCV_DATA_DIR)) {
    const std::string ext = entry.path().extension().string();
    if (ext != ".png" && ext != ".jpg") continue;
    const cv::Mat image = cv::imread(entry.path().string(), cv::IMREAD_UNCHANGED);
    if (image.empty()) continue;
    std::ifstream in(entry.path(), std::ios::binary);
    const Bytes bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const DeclaredSize d = of(bytes);
    ASSERT_EQ(d.kind, DeclaredSize::kKnown) << entry.path();
    EXPECT_EQ(d.width, static_cast<std::uint64_t>(image.cols)) << entry.path();
    EXPECT_EQ(d.height, static_cast<std::uint64_t>(image.rows)) << entry.path();
    ++checked;
  }
  EXPECT_GT(checked, 40) << "opencv-doc's images (apt-get install opencv-doc)";
}

TEST(ImageHeader, EachFormatOpenCvWritesDeclaresItsSize) {
  const cv::Mat photo = cv::imread(std::string(KG_OPENCV_DATA_DIR) + "/fruits.jpg");
  ASSERT_FALSE(photo.empty());
  const cv::Mat crop = photo(cv::Rect(3, 5, 301, 199)).clone();
  const cv::Mat gray = cv::imread(std::string(KG_OPENCV_DATA_DIR) + "/fruits.jpg",
                                  cv::IMREAD_GRAYSCALE)(cv::Rect(3, 5, 301, 199))
                           .clone();
  const struct {
    const char* ext;
    const char* format;
    const cv::Mat& image;
  } cases[] = {{".png", "PNG", crop},   {".jpg", "JPEG", crop},  {".bmp", "BMP", crop},
               {".tiff", "TIFF", crop}, {".webp", "WebP", crop}, {".ppm", "PNM", crop},
               {".pgm", "PNM", gray},   {".pbm", "PNM", gray},   {".ras", "Sun raster", crop},
               {".pfm", "PFM", crop}};
  for (const auto& c : cases) {
    cv::Mat image = c.image;
    if (std::string(c.ext) == ".pfm") c.image.convertTo(image, CV_32FC3, 1.0 / 255);
    const Bytes bytes = encode(image, c.ext);
    const DeclaredSize d = of(bytes);
    EXPECT_EQ(d.kind, DeclaredSize::kKnown) << c.ext;
    EXPECT_STREQ(d.format, c.format) << c.ext;
    EXPECT_EQ(d.width, 301u) << c.ext;
    EXPECT_EQ(d.height, 199u) << c.ext;
    EXPECT_TRUE(check_declared_size(bytes, "x").is_ok()) << c.ext;
  }
  // Lossless WebP (VP8L) as well as lossy (VP8).
  Bytes lossless;
  ASSERT_TRUE(cv::imencode(".webp", crop, lossless, {cv::IMWRITE_WEBP_QUALITY, 101}));
  ASSERT_EQ(lossless[15], 'L') << "VP8L";
  EXPECT_EQ(of(lossless).width, 301u);
  EXPECT_EQ(of(lossless).height, 199u);
}

// A PNG signature and IHDR declaring width x height (what a bomb starts with).
Bytes png_declaring(std::uint32_t width, std::uint32_t height) {
  Bytes b = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n', 0, 0, 0, 13, 'I', 'H', 'D', 'R'};
  for (std::uint32_t v : {width, height})
    for (int shift = 24; shift >= 0; shift -= 8) b.push_back(static_cast<std::uint8_t>(v >> shift));
  return b;
}

TEST(ImageHeader, BombsAreRefusedBeforeDecoding) {
  const Status s = check_declared_size(png_declaring(16384, 16384), "bomb.png");
  EXPECT_EQ(s.code(), StatusCode::kResourceExhausted);
  EXPECT_EQ(s.message(), "bomb.png: PNG of 16384x16384 pixels is over " +
                             std::to_string(kMaxImagePixels) + " pixels (the limit), not decoded");
  EXPECT_TRUE(check_declared_size(png_declaring(4096, 4096), "at_limit.png"));
  EXPECT_FALSE(check_declared_size(png_declaring(4097, 4096), "over.png"));
  EXPECT_FALSE(check_declared_size(png_declaring(0xFFFFFFFFu, 0xFFFFFFFFu), "huge.png"));
  // A real JPEG whose frame header is rewritten to declare 30000 x 30000:
  // too large whole or at 1/4 of each side, within the limit at 1/8.
  const cv::Mat photo = cv::imread(std::string(KG_OPENCV_DATA_DIR) + "/fruits.jpg");
  Bytes jpeg = encode(photo, ".jpg");
  for (std::size_t i = 2; i + 8 < jpeg.size(); ++i) {
    if (jpeg[i] == 0xFF && jpeg[i + 1] == 0xC0) {
      jpeg[i + 5] = jpeg[i + 7] = 30000 >> 8;
      jpeg[i + 6] = jpeg[i + 8] = 30000 & 0xFF;
      break;
    }
  }
  ASSERT_EQ(of(jpeg).width, 30000u);
  EXPECT_EQ(check_declared_size(jpeg, "bomb.jpg").code(), StatusCode::kResourceExhausted);
  const Status quarter = check_declared_size(jpeg, "bomb.jpg", 4);
  EXPECT_EQ(quarter.code(), StatusCode::kResourceExhausted);
  EXPECT_NE(quarter.message().find("(1/4: 7500x7500)"), std::string::npos) << quarter.message();
  EXPECT_TRUE(check_declared_size(jpeg, "bomb.jpg", 8));
}

TEST(ImageHeader, FormatsWhoseSizeIsNotReadAreRefused) {
  const Bytes jp2 = {0xFF, 0x4F, 0xFF, 0x51, 0, 0};
  const Status s = check_declared_size(jp2, "photo.j2k");
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("photo.j2k: JPEG 2000 images are not read"), std::string::npos);
  const std::string hdr = "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 30000 +X 30000\n";
  EXPECT_FALSE(check_declared_size(Bytes(hdr.begin(), hdr.end()), "sky.hdr"));
}

TEST(ImageHeader, BrokenHeadersAreLeftToTheDecoder) {
  for (const std::string& text :
       {std::string("\x89PNG\r\n\x1a\n garbage"), std::string("\xFF\xD8\xFF"), std::string("BM"),
        std::string("P6\n"), std::string("II*\0\xff\xff\xff\xff", 8), std::string("not an image"),
        std::string()}) {
    const Bytes bytes(text.begin(), text.end());
    EXPECT_NE(of(bytes).kind, DeclaredSize::kKnown) << text;
    EXPECT_TRUE(check_declared_size(bytes, "broken")) << text;
  }
}

// An extended (VP8X) WebP header that ends where its canvas size does: the
// 24-bit width and height are read from its last six bytes and nothing after
// them (reading past a 30-byte file was a heap overflow fuzz_pgm found).
TEST(ImageHeader, ShortestExtendedWebpIsReadWithinItsBytes) {
  Bytes header(30, 0);
  const char riff[] = "RIFF\x16\0\0\0WEBPVP8X";  // 16 bytes and the literal's NUL
  std::copy(riff, riff + 16, header.begin());
  const std::uint32_t width_minus_one = 0x0102FF, height_minus_one = 0x000300;
  for (int i = 0; i < 3; ++i) {
    header[static_cast<std::size_t>(24 + i)] =
        static_cast<std::uint8_t>(width_minus_one >> (8 * i));
    header[static_cast<std::size_t>(27 + i)] =
        static_cast<std::uint8_t>(height_minus_one >> (8 * i));
  }
  const DeclaredSize size = of(header);
  ASSERT_EQ(size.kind, DeclaredSize::kKnown);
  EXPECT_STREQ(size.format, "WebP");
  EXPECT_EQ(size.width, width_minus_one + 1u);
  EXPECT_EQ(size.height, height_minus_one + 1u);
}

}  // namespace
}  // namespace kg::platform
