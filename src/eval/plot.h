// Line plots drawn with OpenCV imgproc, in the style of the keygraph
// paper's figures: white background, boxed axes with ticks and tick labels,
// axis labels, a title, and a legend of coloured line samples. Linear or
// base-10 logarithmic y axis. For the evaluation's precision-recall and
// RANSAC-iteration curves.
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace kg {

struct PlotSeries {
  std::string label;
  std::vector<double> x, y;    // NaN or non-finite points break the line
  cv::Scalar colour{0, 0, 0};  // BGR
  bool dashed = false;
  // Drawn this many pixels lower (negative: higher) than its data, so that
  // series with equal values stay visible side by side; a few pixels only.
  int offset_y = 0;
  // A marker (filled circle) at one point, e.g. the default threshold; -1: none.
  int marker = -1;
  // A marker at every point, of this shape (0 circle, 1 square, 2 triangle,
  // 3 diamond, then again), also in the legend; -1: none. Series that
  // coincide stay told apart by their markers.
  int point_shape = -1;
  // With point_shape: when not empty, only the points whose entry here is
  // non-zero are marked (e.g. a bin's median on a step drawn across the bin).
  std::vector<char> marked{};
};

// Where the legend goes: a corner inside the axes, or to their right
// (the axes then narrow to make room: the legend never covers the data).
enum class LegendCorner { kTopRight, kTopLeft, kBottomLeft, kBottomRight, kOutsideRight };

struct PlotSpec {
  std::string title, x_label, y_label;
  double x_min = 0, x_max = 1, y_min = 0, y_max = 1;  // y: values, also with log_y
  bool log_y = false;                                 // y_min must then be > 0
  std::vector<PlotSeries> series;
  LegendCorner legend = LegendCorner::kTopRight;
  int width = 560, height = 420;
};

// Pixel positions of data coordinates inside a rendered plot.
class PlotFrame {
 public:
  explicit PlotFrame(const PlotSpec& spec);
  cv::Point2d to_pixel(double x, double y) const;
  cv::Rect area() const { return area_; }  // the axes' box

 private:
  double x_min_, x_max_, y_lo_, y_hi_;
  bool log_y_;
  cv::Rect area_;
};

// Renders the plot (8-bit BGR, spec.width x spec.height).
cv::Mat render_plot(const PlotSpec& spec);

// Panels side by side, `columns` per row, on a white background.
cv::Mat tile_plots(const std::vector<cv::Mat>& panels, int columns);

// Standard series colours (BGR), distinct in print and on screen.
cv::Scalar plot_colour(int i);

}  // namespace kg
