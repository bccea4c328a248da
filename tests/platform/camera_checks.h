// What a camera source must deliver, checked the same way for V4L2 and
// libcamera on a real camera: `count` frames out of at most three times as
// many tries (a bad frame is skipped, as an application skips it), each with
// pixels, at `width` x `height` when those are not 0, with rising sequence
// numbers and timestamps.
#pragma once

#include <cstdint>

#include <gtest/gtest.h>

#include "platform/frame_source.h"

namespace kg::platform::test {

inline void expect_ordered_frames(FrameSource& src, int count, int width = 0, int height = 0) {
  Frame f;
  std::uint64_t last_seq = 0, last_ts = 0;
  int got = 0;
  for (int i = 0; i < 3 * count && got < count; ++i) {
    const Status n = src.next(f, 2000);
    if (is_bad_frame(n)) continue;
    ASSERT_TRUE(n) << n.message();
    if (width > 0) {
      EXPECT_EQ(f.image.width, width);
    }
    if (height > 0) {
      EXPECT_EQ(f.image.height, height);
    }
    EXPECT_FALSE(f.image.empty());
    if (got > 0) {
      EXPECT_GT(f.sequence, last_seq);
      EXPECT_GT(f.timestamp_ns, last_ts);
    }
    last_seq = f.sequence;
    last_ts = f.timestamp_ns;
    ++got;
  }
  EXPECT_EQ(got, count);
}

}  // namespace kg::platform::test
