// Golden frames without OpenCV, so that the ARM cross-builds run them under
// qemu: a stored index of opencv-doc's box.png (tests/data/frames-box.kgi)
// and PGM frames made at build time from opencv-doc's PNGs
// (tests/tools/png_to_pgm.py). The box must be found in each frame with its
// corners within half a pixel of the stored ones (tests/data/frames-corners.txt:
// the x86-64 reference; other targets' floating point differs in the last
// bits), and detect() must not allocate on the heap, however often it runs.
//
// After a deliberate change of detection, regenerate the stored corners on
// x86-64 and commit them (how: tests/data/frames-corners.txt):
//   KG_UPDATE_GOLDEN=1 <build>/tests/core/test_golden_frames
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "keygraph/detector.h"
#include "keygraph/model_index.h"
#include "platform/files/pgm.h"
#include "support/alloc_counter.h"

namespace kg {
namespace {

constexpr double kCornerTolerance = 0.5;  // pixels

// One line of frames-corners.txt: a frame, the model found in it, its four
// corners (x y, in the order of Detection::corners).
struct Expected {
  std::string frame;
  std::string model;
  Point2f corners[4];
};

const std::string kIndexPath = KG_GOLDEN_DATA_DIR "/frames-box.kgi";
const std::string kExpectedPath = KG_GOLDEN_DATA_DIR "/frames-corners.txt";

// The stored corners; '#' starts a comment line. Fails the test on a
// malformed line.
std::vector<Expected> read_expected() {
  std::vector<Expected> out;
  std::ifstream in(kExpectedPath);
  EXPECT_TRUE(in.good()) << "cannot read " << kExpectedPath;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    Expected e;
    fields >> e.frame >> e.model;
    for (Point2f& c : e.corners) fields >> c.x >> c.y;
    std::string extra;
    if (fields.fail() || (fields >> extra)) {
      ADD_FAILURE() << kExpectedPath << ":" << number << ": expected FRAME MODEL and 8 numbers";
      return {};
    }
    out.push_back(e);
  }
  return out;
}

// The header and one line per detection, as read_expected() reads them.
void write_expected(const std::vector<Expected>& found) {
  std::ifstream old(kExpectedPath);
  std::string header, line;
  while (std::getline(old, line) && (line.empty() || line[0] == '#')) header += line + "\n";
  std::ofstream out(kExpectedPath + ".tmp");
  out << header;
  for (const Expected& e : found) {
    out << e.frame << ' ' << e.model;
    char number[32];
    for (const Point2f& c : e.corners) {
      std::snprintf(number, sizeof number, " %.4f %.4f", c.x, c.y);
      out << number;
    }
    out << '\n';
  }
  out.close();
  ASSERT_TRUE(out.good()) << "cannot write " << kExpectedPath;
  ASSERT_EQ(std::rename((kExpectedPath + ".tmp").c_str(), kExpectedPath.c_str()), 0);
  std::printf("wrote %s (%zu detections)\n", kExpectedPath.c_str(), found.size());
}

struct Frame {
  std::string name;
  platform::GrayImage image;
};

class GoldenFrames : public ::testing::Test {
 protected:
  void SetUp() override {
    const Status opened = ModelIndex::open(kIndexPath, index_);
    ASSERT_TRUE(opened) << opened.message();
    expected_ = read_expected();
    ASSERT_FALSE(expected_.empty()) << "no stored corners in " << kExpectedPath;
    for (const Expected& e : expected_) {
      Frame f{e.frame, {}};
      const Status read = platform::read_pgm(KG_GOLDEN_FRAMES_DIR "/" + e.frame, f.image);
      ASSERT_TRUE(read) << read.message();
      frames_.push_back(std::move(f));
    }
  }

  ModelIndex index_;
  std::vector<Expected> expected_;
  std::vector<Frame> frames_;
};

double corner_error(const Point2f& a, const Point2f& b) {
  return std::max(std::abs(a.x - b.x), std::abs(a.y - b.y));
}

bool updating() {
  const char* update = std::getenv("KG_UPDATE_GOLDEN");
  return update != nullptr && std::string(update) == "1";
}

TEST_F(GoldenFrames, BoxFoundAtTheStoredCorners) {
  Detector detector(index_);
  ASSERT_TRUE(detector.status()) << detector.status().message();
  std::vector<Expected> found;
  for (std::size_t i = 0; i < frames_.size(); ++i) {
    SCOPED_TRACE(frames_[i].name);
    DetectionList out;
    const Status s = detector.detect(frames_[i].image.view(), out);
    ASSERT_TRUE(s) << s.message();
    ASSERT_EQ(out.size(), 1u) << "expected one detection: " << expected_[i].model;
    const Detection& d = out[0];
    Expected e{frames_[i].name, std::string(d.model_name), {}};
    for (int c = 0; c < 4; ++c) e.corners[c] = d.corners[c];
    found.push_back(e);
    if (updating()) continue;
    EXPECT_EQ(e.model, expected_[i].model);
    for (int c = 0; c < 4; ++c) {
      EXPECT_LE(corner_error(d.corners[c], expected_[i].corners[c]), kCornerTolerance)
          << "corner " << c << ": (" << d.corners[c].x << ", " << d.corners[c].y << "), stored ("
          << expected_[i].corners[c].x << ", " << expected_[i].corners[c].y << ")";
    }
  }
  if (updating()) write_expected(found);
}

TEST_F(GoldenFrames, DetectAllocatesNothing) {
  Detector detector(index_);
  ASSERT_TRUE(detector.status()) << detector.status().message();
  DetectionList out;
  int found = 0;
  constexpr int kRuns = 10;
  const test::AllocationCounter allocations;
  for (int run = 0; run < kRuns; ++run) {
    const Frame& f = frames_[static_cast<std::size_t>(run) % frames_.size()];
    const Status s = detector.detect(f.image.view(), out);
    ASSERT_TRUE(s) << s.message();
    found += out.size() == 1 ? 1 : 0;
  }
  EXPECT_EQ(allocations.count(), 0) << "detect() allocated on the heap";
  EXPECT_EQ(detector.workspace_used(), detector.workspace_bytes())
      << "detect() took more of its workspace";
  EXPECT_EQ(found, kRuns) << "the box is found in every frame every time";
}

}  // namespace
}  // namespace kg
