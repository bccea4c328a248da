// The file source end to end on a temporary directory: PGM files written by
// the library and by hand (comments, 16-bit, maxval scaling), sorted
// reading order, end of stream, loop, corrupt files; PNGs through OpenCV
// when the build decodes them (real opencv-doc images compared pixel for
// pixel with cv::imread), a clear error otherwise.
#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "platform/files/file_source.h"
#include "platform/files/pgm.h"
#include "support/temp_dir.h"

#if KG_TEST_OPENCV
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#endif

namespace kg::platform {
namespace {

using test::TempDir;
namespace fs = std::filesystem;

void write_bytes(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
}

GrayImage pattern(int w, int h, int seed) {
  GrayImage g;
  g.width = w;
  g.height = h;
  g.pixels.resize(static_cast<std::size_t>(w * h));
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      g.pixels[y * w + x] = static_cast<std::uint8_t>((x * 3 + y * 17 + seed * 41) & 0xff);
    }
  }
  return g;
}

void expect_same(const ImageView& a, const ImageView& b) {
  ASSERT_EQ(a.width, b.width);
  ASSERT_EQ(a.height, b.height);
  for (int y = 0; y < a.height; ++y) {
    for (int x = 0; x < a.width; ++x) ASSERT_EQ(a.at(x, y), b.at(x, y)) << x << "," << y;
  }
}

TEST(Pgm, WriteThenReadRoundTrips) {
  TempDir dir;
  ASSERT_FALSE(dir.path().empty());
  const GrayImage img = pattern(37, 11, 1);
  // A strided view: only the first 37 of 40 bytes per row are pixels.
  std::vector<std::uint8_t> strided(40 * 11, 0xEE);
  for (int y = 0; y < 11; ++y) {
    for (int x = 0; x < 37; ++x) strided[y * 40 + x] = img.pixels[y * 37 + x];
  }
  const std::string path = dir.file("a.pgm");
  ASSERT_TRUE(write_pgm(path, ImageView(strided.data(), 37, 11, 40)));
  GrayImage back;
  ASSERT_TRUE(read_pgm(path, back));
  expect_same(back.view(), img.view());
  // Nothing but the image is left in the directory (no temporary file).
  EXPECT_EQ(std::distance(fs::directory_iterator(dir.path()), fs::directory_iterator()), 1);
}

TEST(Pgm, HandWrittenHeadersWithCommentsAndMaxvals) {
  const std::string eight = std::string("P5\n# a comment\n3 # inline\n2\n255\n") +
                            std::string("\x00\x01\x7f\x80\xfe\xff", 6);
  GrayImage g;
  ASSERT_TRUE(
      decode_pgm(reinterpret_cast<const std::uint8_t*>(eight.data()), eight.size(), "8", g));
  ASSERT_EQ(g.width, 3);
  ASSERT_EQ(g.height, 2);
  EXPECT_EQ(g.pixels, (std::vector<std::uint8_t>{0, 1, 127, 128, 254, 255}));

  // maxval 15: samples scale to 0..255 (v * 255 / 15, rounded).
  const std::string four = std::string("P5 2 1 15\t") + std::string("\x0f\x07", 2);
  ASSERT_TRUE(decode_pgm(reinterpret_cast<const std::uint8_t*>(four.data()), four.size(), "4", g));
  EXPECT_EQ(g.pixels, (std::vector<std::uint8_t>{255, 119}));

  // 16-bit big-endian samples.
  const std::string sixteen = std::string("P5\n2 1\n65535\n") + std::string("\xff\xff\x80\x00", 4);
  ASSERT_TRUE(
      decode_pgm(reinterpret_cast<const std::uint8_t*>(sixteen.data()), sixteen.size(), "16", g));
  EXPECT_EQ(g.pixels, (std::vector<std::uint8_t>{255, 128}));
}

TEST(Pgm, CorruptFilesGiveOneClearError) {
  struct Case {
    std::string bytes;
    std::string message;
  };
  const Case cases[] = {
      {"", "no P5 magic"},
      {"GIF89a", "no P5 magic"},
      {"P2\n2 2\n255\n0 0 0 0\n", "P2 netpbm file: only binary gray PGM (P5)"},
      {"P6\n1 1\n255\n\x01\x02\x03", "P6 netpbm file"},
      {"P5\n2 2\n255\n\x01\x02\x03", "truncated PGM: 3 of 4 bytes"},
      {"P5\n2 2\n65535\n\x01\x02\x03\x04", "truncated PGM: 4 of 8 bytes"},
      {"P5\n0 2\n255\n", "PGM size 0x2"},
      {"P5\n40000 2\n255\n", "PGM size 40000x2"},
      {"P5\n2 2\n0\n\x00\x00\x00\x00", "maxval 0"},
      {"P5\n2 2\n70000\n", "maxval 70000"},
      {"P5\n2 x\n255\n", "malformed PGM header"},
      {"P52 2 255 ", "malformed PGM header"},
      {"P5\n2 2\n255", "malformed PGM header"},
      {"P5\n99999999999 2\n255\n", "malformed PGM header"},
  };
  for (const Case& c : cases) {
    GrayImage g;
    const Status s =
        decode_pgm(reinterpret_cast<const std::uint8_t*>(c.bytes.data()), c.bytes.size(), "f", g);
    EXPECT_EQ(s.code(), StatusCode::kCorruptData) << c.message;
    EXPECT_NE(s.message().find(c.message), std::string::npos) << s.message();
    EXPECT_EQ(s.message().rfind("f: ", 0), 0u) << s.message();
  }
  GrayImage g;
  EXPECT_EQ(read_pgm("/nonexistent/x.pgm", g).code(), StatusCode::kNotFound);
  EXPECT_EQ(read_pgm("/", g).code(), StatusCode::kIoError);
}

// Writes frame_00N.pgm (N = 2, 0, 1: out of order), a text file and a
// subdirectory, which the directory listing ignores.
void make_pgm_dir(const TempDir& dir) {
  for (int i : {2, 0, 1}) {
    const GrayImage img = pattern(20 + i, 10 + i, i);
    ASSERT_TRUE(write_pgm(dir.file("frame_00" + std::to_string(i) + ".pgm"), img.view()));
  }
  write_bytes(dir.file("notes.txt"), "not an image");
  fs::create_directory(dir.path() / "sub.png");
}

TEST(FileSource, ReadsADirectoryInSortedOrderThenEnds) {
  TempDir dir;
  make_pgm_dir(dir);
  FileSource src({dir.path().string()});
  ASSERT_TRUE(src.start());
  ASSERT_EQ(src.files().size(), 3u);
  Frame f;
  std::uint64_t last_ts = 0;
  for (int i = 0; i < 3; ++i) {
    const Status s = src.next(f, 0);
    ASSERT_TRUE(s) << s.message();
    EXPECT_EQ(f.sequence, static_cast<std::uint64_t>(i));
    EXPECT_GE(f.timestamp_ns, last_ts);
    last_ts = f.timestamp_ns;
    expect_same(f.image, pattern(20 + i, 10 + i, i).view());
  }
  const Status end = src.next(f, 0);
  EXPECT_TRUE(is_end_of_stream(end)) << end.message();
  EXPECT_NE(end.message().find("end of stream after 3 files"), std::string::npos);
  EXPECT_TRUE(is_end_of_stream(src.next(f, 0)));  // stays at the end
  EXPECT_NE(src.description().find("3 images"), std::string::npos) << src.description();
  src.stop();
  src.stop();
}

TEST(FileSource, LoopsAndRestarts) {
  TempDir dir;
  make_pgm_dir(dir);
  FileSource src({dir.path().string()}, FileSourceOptions{true});
  ASSERT_TRUE(src.start());
  Frame f;
  for (int i = 0; i < 7; ++i) {
    ASSERT_TRUE(src.next(f, 0));
    EXPECT_EQ(f.sequence, static_cast<std::uint64_t>(i));
    EXPECT_EQ(f.image.width, 20 + i % 3);
  }
  // start() again begins at the first file.
  ASSERT_TRUE(src.start());
  ASSERT_TRUE(src.next(f, 0));
  EXPECT_EQ(f.sequence, 0u);
  EXPECT_EQ(f.image.width, 20);
}

TEST(FileSource, ExplicitListKeepsItsOrder) {
  TempDir dir;
  make_pgm_dir(dir);
  FileSource src({dir.file("frame_002.pgm"), dir.file("frame_000.pgm")});
  ASSERT_TRUE(src.start());
  Frame f;
  ASSERT_TRUE(src.next(f, 0));
  EXPECT_EQ(f.image.width, 22);
  ASSERT_TRUE(src.next(f, 0));
  EXPECT_EQ(f.image.width, 20);
  EXPECT_TRUE(is_end_of_stream(src.next(f, 0)));
}

TEST(FileSource, CorruptFileIsABadFrameAndReadingGoesOn) {
  TempDir dir;
  make_pgm_dir(dir);
  write_bytes(dir.file("frame_001.pgm"), "P5\n4 4\n255\nxy");  // truncated
  FileSource src({dir.path().string()});
  ASSERT_TRUE(src.start());
  Frame f;
  ASSERT_TRUE(src.next(f, 0));
  EXPECT_EQ(f.image.width, 20);
  const Status bad = src.next(f, 0);
  EXPECT_TRUE(is_bad_frame(bad)) << bad.message();
  EXPECT_NE(bad.message().find("frame_001.pgm: truncated PGM"), std::string::npos) << bad.message();
  ASSERT_TRUE(src.next(f, 0));
  EXPECT_EQ(f.image.width, 22);
  EXPECT_EQ(f.sequence, 1u);  // counts delivered frames
  EXPECT_TRUE(is_end_of_stream(src.next(f, 0)));
}

// last_path() names the file behind each frame, bad ones included, so a
// caller can label frames even when sequence numbers skip bad files.
TEST(FileSource, LastPathNamesEveryFileRead) {
  TempDir dir;
  make_pgm_dir(dir);
  write_bytes(dir.file("frame_001.pgm"), "P5\n4 4\n255\nxy");  // truncated
  FileSource src({dir.path().string()});
  EXPECT_EQ(src.last_path(), "");
  ASSERT_TRUE(src.start());
  EXPECT_EQ(src.last_path(), "");
  Frame f;
  std::vector<std::string> names;
  for (Status s = src.next(f, 0); !is_end_of_stream(s); s = src.next(f, 0)) {
    names.push_back(fs::path(src.last_path()).filename().string() + (s ? "" : " bad"));
  }
  EXPECT_EQ(names,
            (std::vector<std::string>{"frame_000.pgm", "frame_001.pgm bad", "frame_002.pgm"}));
  src.stop();
  EXPECT_EQ(src.last_path(), "");
}

TEST(FileSource, ReadImageDecodesOneFileWithOneClearError) {
  TempDir dir;
  ASSERT_TRUE(write_pgm(dir.file("a.pgm"), pattern(9, 5, 2).view()));
  GrayImage g;
  ASSERT_TRUE(read_image(dir.file("a.pgm"), g));
  expect_same(g.view(), pattern(9, 5, 2).view());

  Status s = read_image(dir.file("missing.pgm"), g);
  EXPECT_EQ(s.code(), StatusCode::kNotFound);
  EXPECT_NE(s.message().find("missing.pgm"), std::string::npos) << s.message();
  write_bytes(dir.file("truncated.pgm"), "P5\n4 4\n255\nxy");
  s = read_image(dir.file("truncated.pgm"), g);
  EXPECT_EQ(s.code(), StatusCode::kCorruptData);
  EXPECT_NE(s.message().find("truncated.pgm: truncated PGM"), std::string::npos) << s.message();
  write_bytes(dir.file("text.png"), "not an image");
  s = read_image(dir.file("text.png"), g);
  EXPECT_EQ(s.code(), StatusCode::kCorruptData);
  EXPECT_NE(s.message().find("text.png: not a"), std::string::npos) << s.message();
}

TEST(FileSource, FileRemovedAfterStartIsABadFrame) {
  TempDir dir;
  make_pgm_dir(dir);
  FileSource src({dir.path().string()});
  ASSERT_TRUE(src.start());
  fs::remove(dir.file("frame_000.pgm"));
  Frame f;
  const Status s = src.next(f, 0);
  EXPECT_TRUE(is_bad_frame(s)) << s.message();
  EXPECT_NE(s.message().find("frame_000.pgm: no such file"), std::string::npos) << s.message();
  EXPECT_TRUE(src.next(f, 0));
}

TEST(FileSource, MissingOrEmptyInputsFailAtStart) {
  TempDir dir;
  FileSource empty({dir.path().string()});
  Status s = empty.start();
  EXPECT_EQ(s.code(), StatusCode::kNotFound);
  EXPECT_NE(s.message().find("no image files"), std::string::npos) << s.message();

  FileSource missing({dir.file("nope")});
  s = missing.start();
  EXPECT_EQ(s.code(), StatusCode::kNotFound);
  EXPECT_NE(s.message().find("nope: no such file or directory"), std::string::npos) << s.message();

  FileSource none({});
  EXPECT_EQ(none.start().code(), StatusCode::kNotFound);

  Frame f;
  FileSource unstarted({dir.path().string()});
  EXPECT_EQ(unstarted.next(f, 0).code(), StatusCode::kInvalidArgument);

  std::vector<std::string> listed;
  EXPECT_EQ(list_image_files(dir.file("nope"), listed).code(), StatusCode::kNotFound);
  write_bytes(dir.file("plain.pgm"), "x");
  EXPECT_EQ(list_image_files(dir.file("plain.pgm"), listed).code(), StatusCode::kIoError);
  FileSource under_file({dir.file("plain.pgm") + "/x.pgm"});  // ENOTDIR counts as missing
  EXPECT_EQ(under_file.start().code(), StatusCode::kNotFound);
}

TEST(FileSource, ImageExtensionsAreCaseInsensitive) {
  TempDir dir;
  for (const char* name : {"B.PGM", "a.png", "c.JPEG", "d.txt", "e.pgm~", "f"}) {
    write_bytes(dir.file(name), "x");
  }
  std::vector<std::string> listed;
  ASSERT_TRUE(list_image_files(dir.path().string(), listed));
  ASSERT_EQ(listed.size(), 3u);
  EXPECT_EQ(fs::path(listed[0]).filename(), "B.PGM");  // byte order: uppercase first
  EXPECT_EQ(fs::path(listed[1]).filename(), "a.png");
  EXPECT_EQ(fs::path(listed[2]).filename(), "c.JPEG");
}

#if KG_TEST_OPENCV
// PNGs (a real opencv-doc image and a written one) mixed with PGMs, read
// through OpenCV and compared with cv::imread.
TEST(FileSource, PngAndPgmMixedThroughOpenCv) {
  ASSERT_TRUE(file_source_uses_opencv());
  TempDir dir;
  const std::string box = std::string(KG_OPENCV_DATA_DIR) + "/box.png";
  ASSERT_TRUE(fs::exists(box)) << box;
  fs::copy_file(box, dir.path() / "1_box.png");
  const GrayImage p = pattern(33, 17, 5);
  const cv::Mat written(p.height, p.width, CV_8U, const_cast<std::uint8_t*>(p.pixels.data()));
  ASSERT_TRUE(cv::imwrite(dir.file("2_pattern.png"), written));
  ASSERT_TRUE(write_pgm(dir.file("0_first.pgm"), pattern(8, 8, 0).view()));
  ASSERT_TRUE(cv::imwrite(dir.file("3_opencv.pgm"), written));  // OpenCV's own PGM writer

  FileSource src({dir.path().string()});
  ASSERT_TRUE(src.start());
  EXPECT_NE(src.description().find("OpenCV"), std::string::npos);
  Frame f;
  ASSERT_TRUE(src.next(f, 0));
  expect_same(f.image, pattern(8, 8, 0).view());
  ASSERT_TRUE(src.next(f, 0));
  const cv::Mat ref = cv::imread(box, cv::IMREAD_GRAYSCALE);
  ASSERT_FALSE(ref.empty());
  expect_same(f.image,
              ImageView(ref.data, ref.cols, ref.rows, static_cast<std::ptrdiff_t>(ref.step)));
  ASSERT_TRUE(src.next(f, 0));
  expect_same(f.image, p.view());
  ASSERT_TRUE(src.next(f, 0));
  expect_same(f.image, p.view());
  EXPECT_TRUE(is_end_of_stream(src.next(f, 0)));

  GrayImage g;
  ASSERT_TRUE(read_image(box, g));
  expect_same(g.view(),
              ImageView(ref.data, ref.cols, ref.rows, static_cast<std::ptrdiff_t>(ref.step)));
}

TEST(FileSource, UndecodableImageIsABadFrame) {
  TempDir dir;
  write_bytes(dir.file("broken.png"), "\x89PNG\r\n\x1a\n garbage");
  FileSource src({dir.path().string()});
  ASSERT_TRUE(src.start());
  Frame f;
  const Status s = src.next(f, 0);
  EXPECT_TRUE(is_bad_frame(s)) << s.message();
  EXPECT_NE(s.message().find("broken.png: not an image OpenCV can decode"), std::string::npos)
      << s.message();
}
#else
TEST(FileSource, WithoutOpenCvOnlyPgmIsRead) {
  ASSERT_FALSE(file_source_uses_opencv());
  TempDir dir;
  write_bytes(dir.file("a.png"), "\x89PNG\r\n\x1a\n");
  ASSERT_TRUE(write_pgm(dir.file("b.pgm"), pattern(4, 4, 0).view()));
  FileSource src({dir.path().string()});
  ASSERT_TRUE(src.start());
  EXPECT_NE(src.description().find("PGM only"), std::string::npos);
  Frame f;
  const Status s = src.next(f, 0);
  EXPECT_TRUE(is_bad_frame(s));
  EXPECT_NE(s.message().find("a.png: not a binary PGM (P5); this build has no OpenCV"),
            std::string::npos)
      << s.message();
  ASSERT_TRUE(src.next(f, 0));
  expect_same(f.image, pattern(4, 4, 0).view());
}
#endif

}  // namespace
}  // namespace kg::platform
