// The file helpers behind the CLI's guarantees (issues 15 and 40): inputs
// opened only as regular files, never blocking, text inputs within a size
// limit; PGM sizes checked before pixels are allocated; truncated JPEGs told
// from whole ones (real opencv-doc JPEGs cut at every 5 %); outputs written
// whole or not at all, never over a device node or an input, several of
// them together; detector limits grown by the frame.
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "platform/files/frame_limits.h"
#include "platform/files/image_limits.h"
#include "platform/files/jpeg_structure.h"
#include "platform/files/output_file.h"
#include "platform/files/output_set.h"
#include "platform/files/pgm.h"
#include "platform/files/regular_file.h"
#include "support/temp_dir.h"

namespace kg::platform {
namespace {

using test::TempDir;
namespace fs = std::filesystem;

std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

TEST(RegularFile, NamesWhatAPathIsWithoutBlocking) {
  TempDir dir;
  ASSERT_EQ(::mkfifo(dir.file("fifo").c_str(), 0600), 0);
  fs::create_directory(dir.file("dir"));
  fs::create_symlink("loop_b", dir.file("loop_a"));
  fs::create_symlink("loop_a", dir.file("loop_b"));
  std::vector<std::uint8_t> bytes;
  const struct {
    std::string path;
    const char* says;
  } cases[] = {{dir.file("fifo"), ": is a FIFO"},
               {dir.file("dir"), ": is a directory"},
               {"/dev/zero", ": is a character device"},
               {dir.file("loop_a"), ": too many levels of symbolic links"},
               {dir.file("missing"), ": no such file"}};
  for (const auto& c : cases) {
    const Status s = read_regular_file(c.path, bytes, 1000);
    ASSERT_FALSE(s) << c.path;
    EXPECT_EQ(s.message(), c.path + c.says);
  }
  std::ofstream(dir.file("big"), std::ios::binary) << std::string(1001, 'x');
  const Status s = read_regular_file(dir.file("big"), bytes, 1000);
  EXPECT_EQ(s.code(), StatusCode::kResourceExhausted) << s.message();
  ASSERT_TRUE(read_regular_file(dir.file("big"), bytes, 1001));
  EXPECT_EQ(bytes.size(), 1001u);
}

TEST(Pgm, DeclaredSizeOverTheLimitIsRefusedBeforeAllocating) {
  // 16384 x 16384 declared, 10 bytes of pixels: refused for its size (not
  // as truncated), and `out` never grew.
  const std::string file = "P5\n16384 16384\n255\n" + std::string(10, '\0');
  GrayImage out;
  const Status s =
      decode_pgm(reinterpret_cast<const std::uint8_t*>(file.data()), file.size(), "bomb.pgm", out);
  ASSERT_FALSE(s);
  EXPECT_EQ(s.message(), "bomb.pgm: PGM size 16384x16384 is over " +
                             std::to_string(kMaxImagePixels) + " pixels (the limit)");
  EXPECT_EQ(out.pixels.capacity(), 0u);
  // At the limit (4096 x 4096) the size is fine and the missing pixels are
  // what is wrong.
  const std::string at_limit = "P5\n4096 4096\n255\n" + std::string(10, '\0');
  const Status t = decode_pgm(reinterpret_cast<const std::uint8_t*>(at_limit.data()),
                              at_limit.size(), "limit.pgm", out);
  EXPECT_NE(t.message().find("truncated PGM"), std::string::npos) << t.message();
}

TEST(Jpeg, TruncatedFilesAreToldFromWholeOnes) {
  const fs::path data = KG_OPENCV_DATA_DIR;
  int files = 0;
  for (const char* name : {"fruits.jpg", "blox.jpg", "leuvenA.jpg", "baboon.jpg"}) {
    std::vector<std::uint8_t> jpeg;
    if (!read_regular_file((data / name).string(), jpeg, 1 << 24)) continue;
    ++files;
    ASSERT_TRUE(is_jpeg(jpeg.data(), jpeg.size())) << name;
    EXPECT_TRUE(jpeg_is_complete(jpeg.data(), jpeg.size())) << name;
    for (int pct = 5; pct < 100; pct += 5) {
      const std::size_t cut = jpeg.size() * static_cast<std::size_t>(pct) / 100;
      EXPECT_FALSE(jpeg_is_complete(jpeg.data(), cut)) << name << " cut at " << pct << " %";
    }
    EXPECT_FALSE(jpeg_is_complete(jpeg.data(), jpeg.size() - 1))
        << name << " without its last byte";
    // Data after the end-of-image marker (e.g. a motion photo's video).
    std::vector<std::uint8_t> trailing = jpeg;
    trailing.insert(trailing.end(), 1000, 0xAB);
    EXPECT_TRUE(jpeg_is_complete(trailing.data(), trailing.size()))
        << name << " with trailing data";
  }
  EXPECT_GE(files, 2) << "opencv-doc JPEGs missing from " << data;
}

TEST(OutputFile, WritesWholeOrNothingThroughAUniqueTemporary) {
  TempDir dir;
  const std::string target = dir.file("out.kgi");
  std::ofstream(dir.file("out.kgi.tmp")) << "user's file";
  {
    OutputFile out;
    ASSERT_TRUE(out.create(target));
    EXPECT_EQ(fs::path(out.temp_path()).parent_path(), fs::path(target).parent_path());
    ASSERT_TRUE(out.write("abc", 3));
    EXPECT_FALSE(fs::exists(target)) << "visible before commit";
  }  // destroyed uncommitted: discarded
  EXPECT_EQ(dir.names(), std::vector<std::string>{"out.kgi.tmp"});
  OutputFile a, b;  // two writers to one target: two temporaries
  ASSERT_TRUE(a.create(target));
  ASSERT_TRUE(b.create(target));
  EXPECT_NE(a.temp_path(), b.temp_path());
  ASSERT_TRUE(a.write("first", 5));
  ASSERT_TRUE(b.write("second", 6));
  ASSERT_TRUE(a.commit());
  EXPECT_EQ(read_text(target), "first");
  ASSERT_TRUE(b.commit());
  EXPECT_EQ(read_text(target), "second");
  EXPECT_EQ(read_text(dir.file("out.kgi.tmp")), "user's file");
  EXPECT_EQ(dir.names(), (std::vector<std::string>{"out.kgi", "out.kgi.tmp"}));
}

TEST(OutputFile, NeverReplacesANonRegularFileOrAnInput) {
  TempDir dir;
  ASSERT_EQ(::mkfifo(dir.file("fifo").c_str(), 0600), 0);
  fs::create_directory(dir.file("dir"));
  OutputFile out;
  Status s = out.create(dir.file("fifo"));
  EXPECT_EQ(s.message(), dir.file("fifo") + ": is a FIFO; outputs replace regular files only");
  s = out.create(dir.file("dir"));
  EXPECT_NE(s.message().find(": is a directory"), std::string::npos) << s.message();
  std::ofstream(dir.file("in.png")) << "input";
  fs::create_symlink("in.png", dir.file("link.png"));
  s = out.create(dir.file("link.png"), {dir.file("other.png"), dir.file("in.png")});
  EXPECT_EQ(s.message(), dir.file("link.png") + ": is also an input (" + dir.file("in.png") +
                             "); choose another output");
  EXPECT_EQ(read_text(dir.file("in.png")), "input");
  EXPECT_EQ(dir.names(), (std::vector<std::string>{"dir", "fifo", "in.png", "link.png"}));
  // A character device: refused, not replaced. As root, a node of our own
  // (a failure must not touch the real /dev/null); otherwise /dev/null
  // itself, which a non-root process could not replace anyway, so only the
  // refusal is asserted there.
  const std::string device = ::geteuid() == 0 ? dir.file("null") : "/dev/null";
  if (::geteuid() == 0) {
    ASSERT_EQ(::mknod(device.c_str(), S_IFCHR | 0666, makedev(1, 3)), 0);
  }
  s = out.create(device);
  EXPECT_NE(s.message().find(": is a character device"), std::string::npos) << s.message();
  struct stat st {};
  ASSERT_EQ(::stat(device.c_str(), &st), 0);
  EXPECT_TRUE(S_ISCHR(st.st_mode));
}

TEST(TextFile, ReadWithinItsLimitOnly) {
  TempDir dir;
  ASSERT_EQ(::mkfifo(dir.file("fifo").c_str(), 0600), 0);
  std::string text;
  // A FIFO would block a stream for ever; /dev/zero would never end.
  Status s = read_text_file(dir.file("fifo"), text, 4096, "a test file");
  EXPECT_EQ(s.message(), dir.file("fifo") + ": is a FIFO");
  s = read_text_file("/dev/zero", text, 4096, "a test file");
  EXPECT_EQ(s.message(), "/dev/zero: is a character device");
  // A sparse file of 5 GB is refused by its size, before a byte is read.
  { std::ofstream(dir.file("sparse")); }
  fs::resize_file(dir.file("sparse"), std::uintmax_t{5} << 30);
  s = read_text_file(dir.file("sparse"), text, 4096, "a test file");
  EXPECT_EQ(s.code(), StatusCode::kResourceExhausted);
  EXPECT_EQ(s.message(),
            dir.file("sparse") + ": 5368709120 bytes, over the 4 KiB a test file may have");
  std::ofstream(dir.file("small"), std::ios::binary) << "line 1\nline 2\n";
  ASSERT_TRUE(read_text_file(dir.file("small"), text, 4096, "a test file"));
  EXPECT_EQ(text, "line 1\nline 2\n");
  EXPECT_EQ(byte_size_text(std::size_t{64} << 20), "64 MiB");
  EXPECT_EQ(byte_size_text(1000), "1000 bytes");
}

TEST(OutputSet, WritesEveryFileOrNone) {
  TempDir dir;
  const std::string root = dir.file("report");
  {
    OutputSet out(root, {});
    ASSERT_TRUE(out.add(root + "/a.csv", std::string("a")));
    ASSERT_TRUE(out.add(root + "/sub/b.png", std::string("b")));
    // Staged, not visible: only the staging directory, in the new root.
    ASSERT_TRUE(fs::is_directory(root));
    EXPECT_FALSE(fs::exists(root + "/a.csv"));
  }  // not committed: the staging directory and the root it made are gone
  EXPECT_TRUE(dir.names().empty());

  OutputSet out(root, {});
  ASSERT_TRUE(out.add(root + "/a.csv", std::string("a")));
  ASSERT_TRUE(out.add(root + "/sub/b.png", std::string("b")));
  EXPECT_EQ(out.add(root + "/./a.csv", std::string("again")).message(),
            root + "/./a.csv: written twice by one command");
  ASSERT_TRUE(out.commit());
  EXPECT_EQ(read_text(root + "/a.csv"), "a");
  EXPECT_EQ(read_text(root + "/sub/b.png"), "b");
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(root)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  EXPECT_EQ(names, (std::vector<std::string>{"a.csv", "sub"}));
}

TEST(OutputSet, ChecksEveryTargetBeforeTheFirstWrite) {
  TempDir dir;
  const std::string root = dir.file("o");
  fs::create_directories(root + "/summary.json");  // a directory where a file goes
  std::ofstream(dir.file("input.txt")) << "input";
  fs::create_symlink("../input.txt", root + "/link.csv");
  std::ofstream(dir.file("precious")) << "precious";
  fs::create_symlink("../precious", root + "/cases.csv.tmp");  // a fixed temporary name
  OutputSet out(root, {dir.file("input.txt")});
  EXPECT_EQ(out.check(root + "/summary.json").message(),
            root + "/summary.json: is a directory; outputs replace regular files only");
  EXPECT_EQ(
      out.check(root + "/link.csv").message(),
      root + "/link.csv: is also an input (" + dir.file("input.txt") + "); choose another output");
  EXPECT_EQ(out.check(dir.file("input.txt") + "/x").message(),
            dir.file("input.txt") + "/x: a path component is not a directory");
  EXPECT_FALSE(out.check(root + "/"));
  ASSERT_TRUE(out.add(root + "/cases.csv", std::string("cases")));
  ASSERT_TRUE(out.commit());
  EXPECT_EQ(read_text(root + "/cases.csv"), "cases");
  EXPECT_EQ(read_text(dir.file("precious")), "precious");
  EXPECT_EQ(read_text(dir.file("input.txt")), "input");
  EXPECT_TRUE(check_output_directory(root));
  EXPECT_TRUE(check_output_directory(dir.file("new/deeper")));
  EXPECT_EQ(check_output_directory(dir.file("input.txt") + "/sub").message(),
            dir.file("input.txt") + ": is a file, not a directory");
}

TEST(OutputSet, RemovesAnEarlierRunsFilesButNeverAnInput) {
  TempDir dir;
  const std::string root = dir.file("o");
  fs::create_directories(root + "/gallery/old");
  std::ofstream(root + "/gallery/old/0001_x.png") << "stale";
  std::ofstream(root + "/gallery/old/0002_in.png") << "an input";
  OutputSet out(root, {root + "/gallery/old/0002_in.png"});
  ASSERT_TRUE(out.add(root + "/gallery/new/0001_x.png", std::string("new")));
  out.remove_at_commit(root + "/gallery/old/0001_x.png");
  out.remove_at_commit(root + "/gallery/old/0002_in.png");
  out.remove_at_commit(root + "/gallery/old");  // not empty: stays
  ASSERT_TRUE(out.commit());
  EXPECT_FALSE(fs::exists(root + "/gallery/old/0001_x.png"));
  EXPECT_EQ(read_text(root + "/gallery/old/0002_in.png"), "an input");
  EXPECT_EQ(read_text(root + "/gallery/new/0001_x.png"), "new");
}

TEST(FrameLimits, GrownByTheFrameNeverToTheProductOfThinFrames) {
  const Limits defaults;
  // A frame that fits keeps the limits (no new workspace).
  EXPECT_EQ(limits_for_frame(defaults, 320, 240).max_width, defaults.max_width);
  const Limits tall = limits_for_frame(defaults, 16, 16384);
  EXPECT_EQ(tall.max_width, defaults.max_width);
  EXPECT_EQ(tall.max_height, 16384);
  // Then a wide one: its own shape (with the default height), not 16384 x 16384.
  const Limits wide = limits_for_frame(tall, 16384, 16);
  EXPECT_EQ(wide.max_width, 16384);
  EXPECT_EQ(wide.max_height, defaults.max_height);
  EXPECT_LE(static_cast<long long>(wide.max_width) * wide.max_height, kMaxImagePixels);
  // Frames of one shape growing: both sides kept while the area allows.
  const Limits both = limits_for_frame(limits_for_frame(defaults, 2000, 480), 640, 2000);
  EXPECT_EQ(both.max_width, 2000);
  EXPECT_EQ(both.max_height, 2000);
  EXPECT_EQ(frame_size_problem(1, 1), "frame 1x1 is too small (under 16 pixels a side)");
  EXPECT_EQ(frame_size_problem(20000, 8),
            "frame 20000x8 is beyond the detector's limits (16384 pixels a side)");
  EXPECT_EQ(frame_size_problem(16, 16), "");
}

}  // namespace
}  // namespace kg::platform
