// The frame blurred as the pipeline blurs it before describing arcs
// (DescriptorParams' blur_sigma), as an OpenCV image for the descriptor tests.
#pragma once

#include <algorithm>
#include <cstdint>

#include <opencv2/core.hpp>

#include "core/image/blur.h"
#include "keygraph/params.h"
#include "support/test_data.h"

namespace kg::test {

inline cv::Mat descriptor_blurred(const cv::Mat& img) {
  Plane<std::uint8_t> dst;
  Plane<float> scratch;
  gaussian_blur(view(img), DescriptorParams{}.blur_sigma, dst, scratch);
  cv::Mat out(dst.height(), dst.width(), CV_8U);
  for (int y = 0; y < dst.height(); ++y)
    std::copy(dst.row(y), dst.row(y) + dst.width(), out.ptr<std::uint8_t>(y));
  return out;
}

}  // namespace kg::test
