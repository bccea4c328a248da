// The indoor signs of the synthetic benchmark: a fixed catalogue of
// distinct designs (exit, toilets, stairs, fire extinguisher, no smoking,
// room numbers, wayfinding ...) in the colour schemes of real safety and
// wayfinding signs, drawn with OpenCV: text in several Hershey fonts and
// sizes, arrows and pictograms (eval/synth/sign_pictograms.h), plain borders,
// large flat areas. A seed varies each design's style (font, stroke weight,
// border, shade, proportions), deterministically.
#pragma once

#include <cstdint>
#include <string>

#include <opencv2/core.hpp>

namespace kg {

int sign_catalogue_size();

struct SignImage {
  std::string name;  // e.g. "exit-right", unique within the catalogue
  cv::Mat image;     // 8-bit BGR, a few hundred pixels a side
};

// Sign `id` (0 <= id < sign_catalogue_size()) in the style drawn from `seed`.
SignImage render_sign(int id, std::uint64_t seed);

}  // namespace kg
