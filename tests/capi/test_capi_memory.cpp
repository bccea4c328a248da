// The C API keeps the runtime's memory contract (tests/core/
// test_runtime_memory.cpp for the C++ API): kg_detect() and
// kg_detector_set_option() allocate nothing, on real frames, however often
// they run; a detector in a caller's workspace allocates only its handle;
// and the C API's detections are the C++ API's, field by field.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <vector>

#include "builder/in_memory_index.h"
#include "builder/index_writer.h"
#include "builder/model_builder.h"
#include "keygraph/detector.h"
#include "keygraph/keygraph.h"
#include "keygraph/tracker.h"
#include "support/alloc_counter.h"
#include "support/test_data.h"

namespace kg {
namespace {

struct Fixture {
  std::unique_ptr<std::uint8_t[]> storage;  // holds the index's bytes, from index.data() on
  std::size_t bytes = 0;
  ModelIndex index;   // the C++ API's view of them
  cv::Mat box_scene;  // box_in_scene.png, 512 x 384
  cv::Mat aero;       // aero1.jpg, 640 x 480
};

// box.png alone, default parameters, serialised into aligned memory.
const Fixture& fixture() {
  static const Fixture* f = [] {
    auto* out = new Fixture;
    std::vector<BuiltModel> models(1);
    const cv::Mat box = test::load_gray(test::opencv_data("box.png"));
    const Params params;
    std::vector<std::uint8_t> bytes;
    if (box.empty() || !build_model(box, "box", params, models[0]) ||
        !serialize_index(models, params, bytes) ||
        !view_aligned_copy(bytes, out->storage, out->index))
      return out;
    out->bytes = bytes.size();
    out->box_scene = test::load_gray(test::opencv_data("box_in_scene.png"));
    out->aero = test::load_gray(test::opencv_data("aero1.jpg"));
    return out;
  }();
  return *f;
}

kg_image image_of(const cv::Mat& m) {
  return kg_image{m.data, m.cols, m.rows, static_cast<std::ptrdiff_t>(m.step)};
}

struct Handles {
  kg_index* index = nullptr;
  kg_detector* detector = nullptr;
  ~Handles() {
    kg_detector_destroy(detector);
    kg_index_destroy(index);
  }
};

void open_index(const Fixture& f, Handles& h) {
  ASSERT_GT(f.bytes, 0u) << "box.png missing or the index failed to build";
  ASSERT_EQ(f.box_scene.cols, 512);
  ASSERT_EQ(f.aero.cols, 640);
  ASSERT_EQ(kg_index_from_memory(f.index.data(), f.bytes, &h.index), KG_OK) << kg_last_error();
}

TEST(CapiMemory, DetectAllocatesNothingOnRealFrames) {
  const Fixture& f = fixture();
  Handles h;
  ASSERT_NO_FATAL_FAILURE(open_index(f, h));
  ASSERT_EQ(kg_detector_create(h.index, nullptr, &h.detector), KG_OK) << kg_last_error();
  const kg_image frames[2] = {image_of(f.box_scene), image_of(f.aero)};
  kg_detection found[KG_MAX_DETECTIONS];
  kg_stats stats;
  int box_found = 0;
  const test::AllocationCounter allocations;
  for (int run = 0; run < 60; ++run) {
    std::size_t count = 0;
    ASSERT_EQ(kg_detect(h.detector, &frames[run % 2], found, KG_MAX_DETECTIONS, &count), KG_OK)
        << kg_last_error();
    ASSERT_EQ(kg_detector_stats(h.detector, &stats), KG_OK);
    if (run % 2 == 0) box_found += count == 1 && std::strcmp(found[0].model_name, "box") == 0;
    // Options between frames, by name: checked, and allocation-free too.
    ASSERT_EQ(kg_detector_set_option(h.detector, "ransac.seed", run % 3 == 0 ? "7" : "1802071399"),
              KG_OK)
        << kg_last_error();
    ASSERT_EQ(kg_detector_set_option(h.detector, "min_confidence", run % 2 == 0 ? "0" : "0.25"),
              KG_OK);
    ASSERT_EQ(kg_detector_set_option(h.detector, "descriptor.max_search_leaves", "8"), KG_OK);
  }
  EXPECT_EQ(allocations.count(), 0) << "kg_detect() or kg_detector_set_option() allocated";
  EXPECT_EQ(box_found, 30) << "the box is found in box_in_scene every time";
}

TEST(CapiMemory, CallersWorkspaceAllocatesOnlyTheHandle) {
  const Fixture& f = fixture();
  Handles h;
  ASSERT_NO_FATAL_FAILURE(open_index(f, h));
  const std::size_t bytes = kg_detector_workspace_bytes(h.index, nullptr);
  ASSERT_GT(bytes, 0u);
  std::vector<std::uint8_t> block(bytes + 64);
  void* workspace = block.data();
  std::size_t room = block.size();
  ASSERT_NE(std::align(64, bytes, workspace, room), nullptr);
  kg_detector* detector = nullptr;
  {
    const test::AllocationCounter allocations;
    ASSERT_EQ(kg_detector_create_in(h.index, nullptr, workspace, bytes, &detector), KG_OK)
        << kg_last_error();
    // The handle; its detector's workspace is the caller's.
    EXPECT_LE(allocations.count(), 1);
  }
  const kg_image frame = image_of(f.box_scene);
  kg_detection found[4];
  std::size_t count = 0;
  const test::AllocationCounter allocations;
  EXPECT_EQ(kg_detect(detector, &frame, found, 4, &count), KG_OK) << kg_last_error();
  EXPECT_EQ(allocations.count(), 0);
  EXPECT_EQ(count, 1u);
  // Before the workspace it lives in goes.
  kg_detector_destroy(detector);
}

// Every field of a detection through the C API equals the C++ API's, and
// a capacity below the detections found keeps the first ones and says so.
TEST(CapiMemory, SameDetectionsAsTheCppApi) {
  const Fixture& f = fixture();
  Handles h;
  ASSERT_NO_FATAL_FAILURE(open_index(f, h));
  Detector detector(f.index);
  DetectionList expected;
  ASSERT_TRUE(detector.detect(test::view(f.box_scene), expected));
  ASSERT_EQ(expected.size(), 1u);
  ASSERT_EQ(kg_detector_create(h.index, nullptr, &h.detector), KG_OK) << kg_last_error();
  const kg_image frame = image_of(f.box_scene);
  kg_detection found[KG_MAX_DETECTIONS];
  std::size_t count = 0;
  ASSERT_EQ(kg_detect(h.detector, &frame, found, KG_MAX_DETECTIONS, &count), KG_OK);
  ASSERT_EQ(count, 1u);
  const Detection& e = expected[0];
  const kg_detection& d = found[0];
  EXPECT_EQ(d.model_id, e.model_id);
  EXPECT_STREQ(d.model_name, "box");
  EXPECT_EQ(d.model_name, kg_index_model_name(h.index, 0)) << "the index's name table";
  for (int i = 0; i < 9; ++i) EXPECT_EQ(d.homography[i], e.homography[static_cast<std::size_t>(i)]);
  for (int c = 0; c < 4; ++c) {
    EXPECT_EQ(d.corners[c][0], double{e.corners[c].x});
    EXPECT_EQ(d.corners[c][1], double{e.corners[c].y});
  }
  EXPECT_EQ(d.inliers, e.inliers);
  EXPECT_EQ(d.inlier_keygraphs, e.inlier_keygraphs);
  EXPECT_EQ(d.score, e.score);
  EXPECT_EQ(d.confidence, e.confidence);
  EXPECT_EQ(d.appearance, e.appearance);
  EXPECT_EQ(d.ransac_iterations, e.ransac_iterations);
  kg_stats stats;
  ASSERT_EQ(kg_detector_stats(h.detector, &stats), KG_OK);
  EXPECT_EQ(stats.keypoints, detector.stats().keypoints);
  EXPECT_EQ(stats.correspondences, detector.stats().correspondences);
  EXPECT_EQ(stats.truncated_detections, 0);
  // No room: nothing written, the stats say one was dropped.
  ASSERT_EQ(kg_detect(h.detector, &frame, nullptr, 0, &count), KG_OK);
  EXPECT_EQ(count, 0u);
  ASSERT_EQ(kg_detector_stats(h.detector, &stats), KG_OK);
  EXPECT_EQ(stats.truncated_detections, 1);
  // Options by name act on the next frame: a confidence floor of 1 drops it.
  ASSERT_EQ(kg_detector_set_option(h.detector, "min_confidence", "1"), KG_OK);
  ASSERT_EQ(kg_detect(h.detector, &frame, found, KG_MAX_DETECTIONS, &count), KG_OK);
  EXPECT_EQ(count, 0u);
  ASSERT_EQ(kg_detector_set_option(h.detector, "min_confidence", "0"), KG_OK);
  ASSERT_EQ(kg_detect(h.detector, &frame, found, KG_MAX_DETECTIONS, &count), KG_OK);
  EXPECT_EQ(count, 1u);
}

// The tracker through the C API follows what kg::Tracker follows on the
// same frames (windows of box_in_scene moving 4 px right, 2 px down each),
// and kg_tracker_process() allocates nothing.
TEST(CapiMemory, TrackerAsTheCppApiWithoutAllocating) {
  const Fixture& f = fixture();
  Handles h;
  ASSERT_NO_FATAL_FAILURE(open_index(f, h));
  const Limits limits = Limits{}.for_frame(448, 336);
  Detector detector(f.index, limits);
  Tracker tracker(detector);
  ASSERT_TRUE(tracker.status()) << tracker.status().message();
  kg_limits c_limits;
  kg_limits_default(&c_limits);
  c_limits.max_width = 448;
  c_limits.max_height = 336;
  ASSERT_EQ(kg_detector_create(h.index, &c_limits, &h.detector), KG_OK) << kg_last_error();
  kg_tracker* c_tracker = nullptr;
  ASSERT_EQ(kg_tracker_create(h.detector, nullptr, &c_tracker), KG_OK) << kg_last_error();
  kg_detection found[KG_MAX_DETECTIONS];
  DetectionList expected;
  int tracked = 0;
  long allocations_in_c = 0;
  for (int k = 0; k < 12; ++k) {
    const cv::Mat window = f.box_scene(cv::Rect(4 * k, 2 * k, 448, 336));
    ASSERT_TRUE(tracker.process(test::view(window), expected));
    const kg_image frame = image_of(window);
    std::size_t count = 0;
    const test::AllocationCounter allocations;
    ASSERT_EQ(kg_tracker_process(c_tracker, &frame, found, KG_MAX_DETECTIONS, &count), KG_OK)
        << kg_last_error();
    allocations_in_c += allocations.count();
    ASSERT_EQ(count, expected.size()) << "frame " << k;
    for (std::size_t i = 0; i < count; ++i) {
      EXPECT_EQ(found[i].track_id, expected[i].track_id);
      EXPECT_EQ(found[i].tracked != 0, expected[i].tracked);
      for (int c = 0; c < 4; ++c) {
        EXPECT_EQ(found[i].corners[c][0], double{expected[i].corners[c].x});
        EXPECT_EQ(found[i].corners[c][1], double{expected[i].corners[c].y});
      }
      tracked += found[i].tracked;
    }
  }
  EXPECT_EQ(allocations_in_c, 0) << "kg_tracker_process() allocated";
  EXPECT_GE(tracked, 10) << "the box is followed between detections";
  kg_tracker_destroy(c_tracker);
}

}  // namespace
}  // namespace kg
