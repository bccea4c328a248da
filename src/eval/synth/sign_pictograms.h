// Pictograms of indoor signs built from OpenCV drawing primitives (filled
// polygons, circles, ellipses, thick lines): people, arrows, stairs, a fire
// extinguisher, a crossed-out cigarette and so on, in the flat two-colour
// look of real safety and wayfinding signs. Drawn into a box of any size,
// in unit coordinates ((0, 0) top-left, (1, 1) bottom-right of the box).
#pragma once

#include <opencv2/core.hpp>

namespace kg {

enum class Pictogram {
  kMan,
  kWoman,
  kRunningMan,
  kDoor,
  kArrowRight,
  kArrowLeft,
  kArrowUp,
  kArrowDown,
  kArrowUpRight,
  kStairsUp,
  kStairsDown,
  kExtinguisher,
  kNoSmoking,
  kWheelchair,
  kLift,
  kFirstAid,
  kInfo,
  kNoEntry,
  kWarning,
  kHighVoltage,
  kFlame,
  kDrinkingWater,
  kCup,
  kWifi,
  kNoPhones,
  kCamera,
  kAssembly,
  kBell,
  kParking,
  kWetFloor,
  kCount
};

const char* pictogram_name(Pictogram p);

// Draws `p` into `box` of the BGR image `img` in `fg` over a background of
// `bg` (used for cut-outs, e.g. the gap between a wheel and its hub).
// Some pictograms carry their own safety colours (the red ring of
// no-smoking, the yellow warning triangle).
void draw_pictogram(cv::Mat& img, Pictogram p, const cv::Rect& box, const cv::Scalar& fg,
                    const cv::Scalar& bg);

}  // namespace kg
