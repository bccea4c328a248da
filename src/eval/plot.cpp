#include "eval/plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <opencv2/imgproc.hpp>

namespace kg {

namespace {

constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;
constexpr double kTickScale = 0.42, kLabelScale = 0.5, kTitleScale = 0.55;
const cv::Scalar kBlack{0, 0, 0}, kGrid{225, 225, 225}, kWhite{255, 255, 255};

// Margins around the axes' box: left for tick labels and the y label,
// bottom for tick labels and the x label, top for the title.
constexpr int kLeft = 70, kRight = 18, kTop = 34, kBottom = 52;

void text(cv::Mat& img, const std::string& s, cv::Point org, double scale, int thickness = 1) {
  cv::putText(img, s, org, kFont, scale, kBlack, thickness, cv::LINE_AA);
}

cv::Size text_size(const std::string& s, double scale, int thickness = 1) {
  int baseline = 0;
  return cv::getTextSize(s, kFont, scale, thickness, &baseline);
}

// "Nice" linear tick step: 1, 2 or 5 times a power of ten, about 5 ticks.
double tick_step(double span) {
  const double raw = span / 5.0;
  const double p = std::pow(10.0, std::floor(std::log10(raw)));
  const double m = raw / p;
  return (m < 1.5 ? 1.0 : m < 3.5 ? 2.0 : m < 7.5 ? 5.0 : 10.0) * p;
}

std::string tick_label(double v, double step) {
  char buf[32];
  const int decimals = std::max(0, static_cast<int>(-std::floor(std::log10(step) + 1e-9)));
  std::snprintf(buf, sizeof(buf), "%.*f", decimals, std::abs(v) < step * 1e-6 ? 0.0 : v);
  return buf;
}

void line(cv::Mat& img, cv::Point2d a, cv::Point2d b, const cv::Scalar& c, int thickness,
          bool dashed, const cv::Rect& clip) {
  cv::Point pa(cvRound(a.x), cvRound(a.y)), pb(cvRound(b.x), cvRound(b.y));
  if (!cv::clipLine(clip, pa, pb)) return;
  if (!dashed) {
    cv::line(img, pa, pb, c, thickness, cv::LINE_AA);
    return;
  }
  const double len = std::hypot(pb.x - pa.x, pb.y - pa.y);
  constexpr double kDash = 7.0;
  for (double t = 0; t < len; t += 2 * kDash) {
    const double t1 = std::min(len, t + kDash);
    const cv::Point2d d(pb.x - pa.x, pb.y - pa.y);
    cv::line(img, cv::Point(cvRound(pa.x + d.x * t / len), cvRound(pa.y + d.y * t / len)),
             cv::Point(cvRound(pa.x + d.x * t1 / len), cvRound(pa.y + d.y * t1 / len)), c,
             thickness, cv::LINE_AA);
  }
}

// The legend's box size: a line sample and the label per series.
constexpr int kLegendRow = 18;
cv::Size legend_size(const PlotSpec& spec) {
  if (spec.series.empty()) return {0, 0};
  int w = 0;
  for (const PlotSeries& s : spec.series) w = std::max(w, text_size(s.label, kTickScale).width);
  return {w + 50, kLegendRow * static_cast<int>(spec.series.size()) + 8};
}

void point_marker(cv::Mat& img, cv::Point p, int shape, const cv::Scalar& c) {
  constexpr int r = 4;
  switch (shape % 4) {
    case 0:
      cv::circle(img, p, r, c, cv::FILLED, cv::LINE_AA);
      break;
    case 1:
      cv::rectangle(img, cv::Rect(p.x - r, p.y - r, 2 * r + 1, 2 * r + 1), c, cv::FILLED);
      break;
    case 2: {
      const cv::Point t[] = {{p.x, p.y - r - 1}, {p.x + r + 1, p.y + r}, {p.x - r - 1, p.y + r}};
      cv::fillConvexPoly(img, t, 3, c, cv::LINE_AA);
      break;
    }
    default: {
      const cv::Point d[] = {
          {p.x, p.y - r - 1}, {p.x + r + 1, p.y}, {p.x, p.y + r + 1}, {p.x - r - 1, p.y}};
      cv::fillConvexPoly(img, d, 4, c, cv::LINE_AA);
      break;
    }
  }
}

}  // namespace

cv::Scalar plot_colour(int i) {
  static const cv::Scalar colours[] = {{200, 80, 0},  {0, 0, 210},    {0, 150, 0},
                                       {0, 140, 255}, {160, 0, 160},  {120, 120, 120},
                                       {140, 90, 40}, {100, 100, 255}};
  return colours[static_cast<std::size_t>(i) % (sizeof(colours) / sizeof(colours[0]))];
}

PlotFrame::PlotFrame(const PlotSpec& spec)
    : x_min_(spec.x_min), x_max_(spec.x_max), log_y_(spec.log_y) {
  y_lo_ = log_y_ ? std::log10(std::max(spec.y_min, 1e-300)) : spec.y_min;
  y_hi_ = log_y_ ? std::log10(std::max(spec.y_max, 1e-300)) : spec.y_max;
  if (!(x_max_ > x_min_)) x_max_ = x_min_ + 1;
  if (!(y_hi_ > y_lo_)) y_hi_ = y_lo_ + 1;
  const int legend = spec.legend == LegendCorner::kOutsideRight && !spec.series.empty()
                         ? legend_size(spec).width + 12
                         : 0;
  area_ = cv::Rect(kLeft, kTop, std::max(10, spec.width - kLeft - kRight - legend),
                   std::max(10, spec.height - kTop - kBottom));
}

cv::Point2d PlotFrame::to_pixel(double x, double y) const {
  const double yv = log_y_ ? (y > 0 ? std::log10(y) : -1e300) : y;
  const double px = area_.x + (x - x_min_) / (x_max_ - x_min_) * (area_.width - 1);
  const double py =
      area_.y + area_.height - 1 - (yv - y_lo_) / (y_hi_ - y_lo_) * (area_.height - 1);
  return {px, std::clamp(py, -1e6, 1e6)};
}

cv::Mat render_plot(const PlotSpec& spec) {
  cv::Mat img(std::max(spec.height, 100), std::max(spec.width, 120), CV_8UC3, kWhite);
  const PlotFrame frame(spec);
  const cv::Rect a = frame.area();
  const int bottom = a.y + a.height - 1, right = a.x + a.width - 1;

  // Grid and ticks.
  const double xs = tick_step(spec.x_max - spec.x_min);
  for (double v = std::ceil(spec.x_min / xs - 1e-9) * xs; v <= spec.x_max + xs * 1e-9; v += xs) {
    const int px = cvRound(frame.to_pixel(v, spec.log_y ? spec.y_min : spec.y_min).x);
    cv::line(img, {px, a.y}, {px, bottom}, kGrid, 1);
    cv::line(img, {px, bottom}, {px, bottom + 5}, kBlack, 1);
    const std::string s = tick_label(v, xs);
    text(img, s, {px - text_size(s, kTickScale).width / 2, bottom + 20}, kTickScale);
  }
  if (spec.log_y) {
    const int lo = static_cast<int>(std::ceil(std::log10(spec.y_min) - 1e-9));
    const int hi = static_cast<int>(std::floor(std::log10(spec.y_max) + 1e-9));
    const int every = std::max(1, (hi - lo + 7) / 8);  // at most ~8 labelled decades
    for (int e = lo; e <= hi; ++e) {
      const int py = cvRound(frame.to_pixel(spec.x_min, std::pow(10.0, e)).y);
      cv::line(img, {a.x, py}, {right, py}, kGrid, 1);
      cv::line(img, {a.x - 5, py}, {a.x, py}, kBlack, 1);
      if ((e - lo) % every != 0) continue;
      // 10 with a raised exponent.
      const std::string base = "10", exp = std::to_string(e);
      const int wb = text_size(base, kTickScale).width,
                we = text_size(exp, kTickScale * 0.75).width;
      const int x0 = a.x - 8 - wb - we;
      text(img, base, {x0, py + 5}, kTickScale);
      text(img, exp, {x0 + wb + 1, py - 3}, kTickScale * 0.75);
    }
  } else {
    const double ys = tick_step(spec.y_max - spec.y_min);
    for (double v = std::ceil(spec.y_min / ys - 1e-9) * ys; v <= spec.y_max + ys * 1e-9; v += ys) {
      const int py = cvRound(frame.to_pixel(spec.x_min, v).y);
      cv::line(img, {a.x, py}, {right, py}, kGrid, 1);
      cv::line(img, {a.x - 5, py}, {a.x, py}, kBlack, 1);
      const std::string s = tick_label(v, ys);
      text(img, s, {a.x - 9 - text_size(s, kTickScale).width, py + 5}, kTickScale);
    }
  }
  cv::rectangle(img, a, kBlack, 1);

  // Labels and title.
  const cv::Size xl = text_size(spec.x_label, kLabelScale);
  text(img, spec.x_label, {a.x + (a.width - xl.width) / 2, img.rows - 10}, kLabelScale);
  if (!spec.y_label.empty()) {
    // Drawn horizontally, then rotated a quarter turn.
    const cv::Size yl = text_size(spec.y_label, kLabelScale);
    cv::Mat label(yl.height + 8, yl.width + 4, CV_8UC3, kWhite);
    text(label, spec.y_label, {2, yl.height + 2}, kLabelScale);
    cv::Mat rotated;
    cv::rotate(label, rotated, cv::ROTATE_90_COUNTERCLOCKWISE);
    const int y0 = std::max(0, a.y + (a.height - rotated.rows) / 2);
    if (y0 + rotated.rows <= img.rows && rotated.cols + 4 <= img.cols)
      rotated.copyTo(img(cv::Rect(4, y0, rotated.cols, rotated.rows)));
  }
  const cv::Size tl = text_size(spec.title, kTitleScale);
  text(img, spec.title, {a.x + (a.width - tl.width) / 2, a.y - 12}, kTitleScale);

  // Series, clipped to the axes' box.
  for (const PlotSeries& s : spec.series) {
    const std::size_t n = std::min(s.x.size(), s.y.size());
    bool have_prev = false;
    cv::Point2d prev;
    for (std::size_t i = 0; i < n; ++i) {
      const bool ok = std::isfinite(s.x[i]) && std::isfinite(s.y[i]) && (!spec.log_y || s.y[i] > 0);
      if (!ok) {
        have_prev = false;
        continue;
      }
      const cv::Point2d p = frame.to_pixel(s.x[i], s.y[i]) + cv::Point2d(0, s.offset_y);
      if (have_prev) line(img, prev, p, s.colour, 2, s.dashed, a);
      if (static_cast<int>(i) == s.marker && a.contains(cv::Point(cvRound(p.x), cvRound(p.y))))
        cv::circle(img, cv::Point(cvRound(p.x), cvRound(p.y)), 5, s.colour, cv::FILLED,
                   cv::LINE_AA);
      const bool mark = s.marked.empty() || (i < s.marked.size() && s.marked[i] != 0);
      if (s.point_shape >= 0 && mark && a.contains(cv::Point(cvRound(p.x), cvRound(p.y))))
        point_marker(img, cv::Point(cvRound(p.x), cvRound(p.y)), s.point_shape, s.colour);
      prev = p;
      have_prev = true;
    }
  }

  // Legend: a line sample and the label per series, in a boxed corner (or
  // right of the axes).
  if (!spec.series.empty()) {
    const int row = kLegendRow;
    const cv::Size size = legend_size(spec);
    const int box_w = size.width, box_h = size.height;
    const bool left =
        spec.legend == LegendCorner::kTopLeft || spec.legend == LegendCorner::kBottomLeft;
    const bool top = spec.legend == LegendCorner::kTopLeft ||
                     spec.legend == LegendCorner::kTopRight ||
                     spec.legend == LegendCorner::kOutsideRight;
    const cv::Rect box(
        spec.legend == LegendCorner::kOutsideRight ? right + 12
        : left                                     ? a.x + 8
                                                   : right - 8 - box_w,
        top ? a.y + (spec.legend == LegendCorner::kOutsideRight ? 0 : 8) : bottom - 8 - box_h,
        box_w, box_h);
    cv::rectangle(img, box, kWhite, cv::FILLED);
    cv::rectangle(img, box, kBlack, 1);
    for (std::size_t i = 0; i < spec.series.size(); ++i) {
      const PlotSeries& s = spec.series[i];
      const int y = box.y + 4 + row * static_cast<int>(i) + row / 2;
      line(img, {box.x + 6.0, y + 0.0}, {box.x + 36.0, y + 0.0}, s.colour, 2, s.dashed, box);
      if (s.point_shape >= 0) point_marker(img, {box.x + 21, y}, s.point_shape, s.colour);
      text(img, s.label, {box.x + 42, y + 5}, kTickScale);
    }
  }
  return img;
}

cv::Mat tile_plots(const std::vector<cv::Mat>& panels, int columns) {
  if (panels.empty() || columns < 1) return {};
  int w = 0, h = 0;
  for (const cv::Mat& p : panels) {
    w = std::max(w, p.cols);
    h = std::max(h, p.rows);
  }
  const int n = static_cast<int>(panels.size());
  const int cols = std::min(columns, n), rows = (n + cols - 1) / cols;
  cv::Mat out(rows * h, cols * w, CV_8UC3, kWhite);
  for (int i = 0; i < n; ++i) {
    const cv::Mat& p = panels[static_cast<std::size_t>(i)];
    cv::Mat bgr;
    if (p.channels() == 1) {
      cv::cvtColor(p, bgr, cv::COLOR_GRAY2BGR);
    } else {
      bgr = p;
    }
    bgr.copyTo(out(cv::Rect((i % cols) * w, (i / cols) * h, bgr.cols, bgr.rows)));
  }
  return out;
}

}  // namespace kg
