// The Tracker on a generated sequence with known motion: opencv-doc's
// box.png rendered into building.jpg (640x480) under a pose that moves,
// turns and grows from frame to frame, then leaves behind an occluder. It
// must follow the box with one id and corners near the truth, detect only
// as often as asked, let go within 2 frames once the box is covered, and
// allocate nothing per frame.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "keygraph/tracker.h"
#include "support/alloc_counter.h"
#include "support/data_dir.h"
#include "support/opencv_scenes.h"
#include "support/test_data.h"

namespace kg {
namespace {

constexpr int kFrames = 40;

struct Sequence {
  test::InMemoryIndex built;
  std::vector<cv::Mat> frames;
  std::vector<std::array<cv::Point2f, 4>> truth;  // the box's corners per frame
  int covered_from = 0;                           // the box is hidden from this frame on
};

// The box's corners at frame i: a smooth path across the frame (about 5 px
// a frame), a slow turn and growth, mild perspective.
std::array<cv::Point2f, 4> corners_at(int i, const cv::Mat& model) {
  const double t = static_cast<double>(i);
  const double cx = 200 + 5.0 * t, cy = 230 + 2.0 * t;
  const double scale = 0.5 + 0.004 * t, angle = 0.01 * t;
  const double w = model.cols * scale / 2, h = model.rows * scale / 2;
  const double ca = std::cos(angle), sa = std::sin(angle);
  const double offsets[4][2] = {{-w, -h}, {w * 0.96, -h * 0.98}, {w, h}, {-w * 0.97, h}};
  std::array<cv::Point2f, 4> out;
  for (int c = 0; c < 4; ++c) {
    const double x = offsets[c][0], y = offsets[c][1];
    out[static_cast<std::size_t>(c)] = cv::Point2f(static_cast<float>(cx + ca * x - sa * y),
                                                   static_cast<float>(cy + sa * x + ca * y));
  }
  return out;
}

const Sequence& sequence() {
  static Sequence s = [] {
    Sequence q;
    const cv::Mat model = test::load_gray(test::opencv_data("box.png"));
    cv::Mat background = test::load_gray(test::opencv_data("building.jpg"));
    EXPECT_FALSE(model.empty());
    EXPECT_FALSE(background.empty());
    EXPECT_TRUE(test::build_in_memory({{"box", model}}, Params{}, q.built));
    cv::resize(background, background, cv::Size(640, 480), 0, 0, cv::INTER_AREA);
    const float w = static_cast<float>(model.cols - 1), h = static_cast<float>(model.rows - 1);
    const std::vector<cv::Point2f> src = {{0.f, 0.f}, {w, 0.f}, {w, h}, {0.f, h}};
    q.covered_from = kFrames - 6;
    for (int i = 0; i < kFrames; ++i) {
      const std::array<cv::Point2f, 4> c = corners_at(i, model);
      const cv::Mat H =
          cv::getPerspectiveTransform(src, std::vector<cv::Point2f>(c.begin(), c.end()));
      cv::Mat frame = background.clone();
      cv::warpPerspective(model, frame, H, frame.size(), cv::INTER_LINEAR, cv::BORDER_TRANSPARENT);
      if (i >= q.covered_from) {
        // An occluder over the whole box (a grey card in front of it).
        cv::rectangle(
            frame, cv::Rect(static_cast<int>(c[0].x) - 40, static_cast<int>(c[0].y) - 40, 360, 260),
            cv::Scalar(128), cv::FILLED);
      }
      q.frames.push_back(frame);
      q.truth.push_back(c);
    }
    return q;
  }();
  return s;
}

double corner_error(const Detection& d, const std::array<cv::Point2f, 4>& truth) {
  // The index's outline is the model image's corners in the same order.
  double worst = 0;
  for (int c = 0; c < 4; ++c)
    worst = std::max(worst, static_cast<double>(
                                std::hypot(d.corners[c].x - truth[static_cast<std::size_t>(c)].x,
                                           d.corners[c].y - truth[static_cast<std::size_t>(c)].y)));
  return worst;
}

TEST(Tracker, FollowsTheBoxWithOneIdAndLetsGoWhenItIsCovered) {
  const Sequence& q = sequence();
  Detector detector(q.built.index, Limits{});
  TrackerOptions options;
  options.detect_interval = 10;
  Tracker tracker(detector, options);
  ASSERT_TRUE(tracker.status()) << tracker.status().message();
  DetectionList found;
  int id = -1, within_2px = 0, tracked = 0, visible = 0, dropped_at = -1;
  for (int i = 0; i < kFrames; ++i) {
    ASSERT_TRUE(tracker.process(test::view(q.frames[static_cast<std::size_t>(i)]), found));
    if (i < q.covered_from) {
      ++visible;
      ASSERT_EQ(found.size(), 1u) << "frame " << i;
      const Detection& d = found[0];
      if (id < 0) id = d.track_id;
      EXPECT_EQ(d.track_id, id) << "frame " << i << ": the id changed";
      tracked += d.tracked ? 1 : 0;
      const double err = corner_error(d, q.truth[static_cast<std::size_t>(i)]);
      within_2px += err <= 2.0 ? 1 : 0;
      EXPECT_LE(err, 5.0) << "frame " << i << (d.tracked ? " (tracked)" : " (detected)");
    } else if (dropped_at < 0 && found.empty()) {
      dropped_at = i;
    }
  }
  EXPECT_GE(id, 0);
  // Detection ran on the first frame and every 10th; the rest were tracked.
  EXPECT_GE(tracked, visible - 5) << "frames confirmed around the prediction";
  EXPECT_GE(within_2px, visible - 2) << "frames with every corner within 2 px";
  ASSERT_GE(dropped_at, 0) << "the covered box was still reported";
  EXPECT_LE(dropped_at - q.covered_from, 1) << "let go within 2 frames";
  const TrackerStats& st = tracker.stats();
  EXPECT_EQ(st.frames, kFrames);
  EXPECT_LE(st.detected_frames, kFrames / 10 + 8);
  std::printf(
      "%d of %d visible frames tracked, %d within 2 px; %lld detected frames; dropped %d "
      "frame(s) after the cover\n",
      tracked, visible, within_2px, st.detected_frames, dropped_at - q.covered_from);
}

TEST(Tracker, AllocatesNothingPerFrame) {
  const Sequence& q = sequence();
  Detector detector(q.built.index, Limits{});
  Tracker tracker(detector);
  DetectionList found;
  ASSERT_TRUE(tracker.process(test::view(q.frames[0]), found));  // detect once
  const test::AllocationCounter counter;
  for (int i = 1; i < kFrames; ++i)
    ASSERT_TRUE(tracker.process(test::view(q.frames[static_cast<std::size_t>(i)]), found));
  EXPECT_EQ(counter.count(), 0);
}

TEST(Tracker, DetectIntervalOneIsDetectionWithIds) {
  const Sequence& q = sequence();
  Detector plain(q.built.index, Limits{});
  Detector detector(q.built.index, Limits{});
  TrackerOptions options;
  options.detect_interval = 1;
  Tracker tracker(detector, options);
  DetectionList a, b;
  int id = -1;
  for (int i = 0; i < 8; ++i) {
    const ImageView frame = test::view(q.frames[static_cast<std::size_t>(i)]);
    ASSERT_TRUE(plain.detect(frame, a));
    ASSERT_TRUE(tracker.process(frame, b));
    ASSERT_EQ(a.size(), 1u);
    ASSERT_EQ(b.size(), 1u);
    EXPECT_FALSE(b[0].tracked);
    EXPECT_EQ(b[0].homography, a[0].homography);  // the detection's own pose
    if (id < 0) id = b[0].track_id;
    EXPECT_EQ(b[0].track_id, id);
  }
}

TEST(Tracker, BadOptionsAndFramesAreRefused) {
  const Sequence& q = sequence();
  Detector detector(q.built.index, Limits{});
  TrackerOptions options;
  options.min_correlation = 1.5;
  EXPECT_EQ(Tracker(detector, options).status().code(), StatusCode::kInvalidArgument);
  options = TrackerOptions{};
  options.detect_interval = 0;
  EXPECT_EQ(Tracker(detector, options).status().code(), StatusCode::kInvalidArgument);
  Tracker tracker(detector);
  cv::Mat large(600, 900, CV_8UC1, cv::Scalar(100));
  DetectionList found;
  EXPECT_EQ(tracker.process(test::view(large), found).code(), StatusCode::kInvalidArgument);
}

// The real hand-held sequence of ../shared/data/real/video (a poster
// behind a shop window rolling to 88 degrees, 1280x720, 50 frames, corners
// on 26 of them) with the model a user would have: the poster rectified
// from another video of it. Detection alone finds it within 15 px on all 26;
// the tracker must too, with one id, detecting only when it has to.
TEST(TrackerRealVideo, PosterBehindAShopWindow) {
  KG_REQUIRE_DATA("real");
  const std::string dir = test::data_dir("real") + "/video/poster-rotation/";
  const cv::Mat model = test::load_gray(dir + "model-other-video.png");
  ASSERT_FALSE(model.empty()) << dir;
  test::InMemoryIndex built;
  ASSERT_TRUE(test::build_in_memory({{"poster", model}}, Params{}, built));
  std::map<std::string, std::array<float, 8>> truth;
  std::ifstream in(dir + "corners_other_model.txt");
  for (std::string line; std::getline(in, line);) {
    std::istringstream fields(line);
    std::string frame;
    std::array<float, 8> c{};
    fields >> frame;
    for (float& v : c) fields >> v;
    if (fields) truth[frame] = c;
  }
  ASSERT_EQ(truth.size(), 26u);
  Detector detector(built.index, Limits{}.for_frame(1280, 720));
  Tracker tracker(detector);
  ASSERT_TRUE(tracker.status()) << tracker.status().message();
  int within_15px = 0, tracked = 0, id = -1, switches = 0;
  DetectionList found;
  for (int i = 1; i <= 50; ++i) {
    char name[16];
    std::snprintf(name, sizeof name, "%08d.jpg", i);
    const cv::Mat frame = test::load_gray(dir + "frames/" + name);
    ASSERT_FALSE(frame.empty()) << name;
    ASSERT_TRUE(tracker.process(test::view(frame), found));
    if (!found.empty()) {
      tracked += found[0].tracked ? 1 : 0;
      if (id >= 0 && found[0].track_id != id) ++switches;
      id = found[0].track_id;
    }
    const auto t = truth.find(name);
    if (t == truth.end() || found.empty()) continue;
    double worst = 0;
    for (int c = 0; c < 4; ++c)
      worst = std::max(
          worst, static_cast<double>(std::hypot(found[0].corners[c].x - t->second[2 * c],
                                                found[0].corners[c].y - t->second[2 * c + 1])));
    within_15px += worst <= 15.0 ? 1 : 0;
  }
  std::printf(
      "poster: %d of 26 annotated frames within 15 px, %d of 50 frames tracked, %d id "
      "switches\n",
      within_15px, tracked, switches);
  EXPECT_EQ(within_15px, 26);
  EXPECT_GE(tracked, 40);  // measured 44: detection on the first frame and every 10th
  EXPECT_EQ(switches, 0);
}

}  // namespace
}  // namespace kg
