// The libcamera source: frames from a real camera when the camera manager
// lists one (skipped with "no camera device: not run" otherwise), and clear
// errors without one.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "camera_checks.h"
#include "platform/libcamera/libcamera_source.h"

namespace kg::platform {
namespace {

// libcamera logs INFO lines to stderr; keep warnings and errors (unless the
// caller set LIBCAMERA_LOG_LEVELS).
const int kQuietLibcamera = ::setenv("LIBCAMERA_LOG_LEVELS", "*:ERROR", 0);

TEST(LibcameraSource, CapturesFramesFromARealCamera) {
  std::vector<std::string> ids;
  const Status listed = list_libcamera_cameras(ids);
  ASSERT_TRUE(listed) << listed.message();
  if (ids.empty()) GTEST_SKIP() << "no camera device: not run (libcamera lists no camera)";
  LibcameraSource src(LibcameraOptions{ids.front(), 640, 480, 4});
  const Status s = src.start();
  ASSERT_TRUE(s) << s.message();
  std::printf("%s\n", src.description().c_str());
  test::expect_ordered_frames(src, 10);
  src.stop();
  // Buffers and requests are set up again from scratch.
  ASSERT_TRUE(src.start());
  Frame f;
  ASSERT_TRUE(src.next(f, 2000));
}

TEST(LibcameraSource, UnknownCameraIdIsNotFound) {
  LibcameraSource src(LibcameraOptions{"/base/keygraph/no-such-camera"});
  const Status s = src.start();
  EXPECT_EQ(s.code(), StatusCode::kNotFound);
  EXPECT_NE(s.message().find("libcamera: no camera with id '/base/keygraph/no-such-camera'"),
            std::string::npos)
      << s.message();
  Frame f;
  EXPECT_EQ(src.next(f, 10).code(), StatusCode::kInvalidArgument);  // not started: no crash
  src.stop();
  EXPECT_NE(src.description().find("not started"), std::string::npos);
}

TEST(LibcameraSource, FirstCameraWhenThereIsNone) {
  std::vector<std::string> ids;
  ASSERT_TRUE(list_libcamera_cameras(ids));
  if (!ids.empty()) GTEST_SKIP() << "camera present: the no camera device error is not checked";
  LibcameraSource src(LibcameraOptions{});
  const Status s = src.start();
  EXPECT_EQ(s.code(), StatusCode::kNotFound);
  EXPECT_EQ(s.message(), "libcamera: no camera device (the camera manager lists none)");
}

// libcamera aborts the process when a second CameraManager exists, so the
// sources share one; it is created and destroyed from several threads here.
TEST(LibcameraSource, CameraManagerIsSharedAcrossThreads) {
  auto work = [] {
    for (int i = 0; i < 20; ++i) {
      std::vector<std::string> ids;
      EXPECT_TRUE(list_libcamera_cameras(ids));
      LibcameraSource src(LibcameraOptions{"/base/keygraph/no-such-camera"});
      EXPECT_EQ(src.start().code(), StatusCode::kNotFound);
    }
  };
  std::thread a(work), b(work);
  a.join();
  b.join();
}

}  // namespace
}  // namespace kg::platform
