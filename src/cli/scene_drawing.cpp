// Pictures of what was found (detect --draw, demo): the scene in colour
// with each detection's outline and model name.
#include <string>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "cli/commands.h"
#include "cli/device/frame_output.h"

namespace kg::cli {

cv::Mat draw_scene(const cv::Mat& scene, const DetectionList& found) {
  cv::Mat canvas;
  if (scene.channels() == 1) {
    cv::cvtColor(scene, canvas, cv::COLOR_GRAY2BGR);
  } else {
    canvas = scene.clone();
  }
  const cv::Scalar colours[] = {{0, 220, 0}, {0, 160, 255}, {255, 80, 0}, {200, 0, 200}};
  const int font = cv::FONT_HERSHEY_SIMPLEX;
  const double font_scale = 0.6;
  int i = 0;
  for (const Detection& d : found) {
    const cv::Scalar c = colours[i++ % 4];
    std::vector<cv::Point> quad;
    for (const Point2f& p : d.corners) quad.emplace_back(cvRound(p.x), cvRound(p.y));
    cv::polylines(canvas, quad, true, c, 2, cv::LINE_AA);
    const std::string name(d.model_name);
    int baseline = 0;
    const cv::Size text = cv::getTextSize(name, font, font_scale, 2, &baseline);
    const LabelPosition place =
        label_position(d, canvas.cols, canvas.rows, text.width, text.height, baseline);
    const cv::Point at(place.x, place.y);
    // A dark edge under the coloured name keeps it readable on any background.
    cv::putText(canvas, name, at, font, font_scale, cv::Scalar(0, 0, 0), 4, cv::LINE_AA);
    cv::putText(canvas, name, at, font, font_scale, c, 2, cv::LINE_AA);
  }
  return canvas;
}

}  // namespace kg::cli
