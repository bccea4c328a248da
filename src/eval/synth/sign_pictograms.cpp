#include "eval/synth/sign_pictograms.h"

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <utility>
#include <vector>

#include <opencv2/imgproc.hpp>

namespace kg {

namespace {

const cv::Scalar kRed{40, 30, 210}, kYellow{0, 200, 250}, kBlack{25, 25, 25}, kWhite{250, 250, 250};

// Unit coordinates of a centred square inside the box, mapped to pixels
// with 4 fractional bits (OpenCV's `shift`) for smooth shapes.
class Pen {
 public:
  Pen(cv::Mat& img, const cv::Rect& box) : img_(img) {
    side_ = std::min(box.width, box.height);
    x0_ = box.x + (box.width - side_) / 2.0;
    y0_ = box.y + (box.height - side_) / 2.0;
  }
  cv::Point p(double u, double v) const {
    return {cvRound((x0_ + u * side_) * kScale), cvRound((y0_ + v * side_) * kScale)};
  }
  int len(double d) const { return std::max(1, cvRound(d * side_)); }
  int flen(double d) const { return cvRound(d * side_ * kScale); }

  void poly(std::initializer_list<std::pair<double, double>> pts, const cv::Scalar& c) {
    std::vector<cv::Point> v;
    for (const auto& [u, w] : pts) v.push_back(p(u, w));
    cv::fillPoly(img_, std::vector<std::vector<cv::Point>>{v}, c, cv::LINE_AA, kShift);
  }
  void rect(double u0, double v0, double u1, double v1, const cv::Scalar& c) {
    poly({{u0, v0}, {u1, v0}, {u1, v1}, {u0, v1}}, c);
  }
  void disc(double u, double v, double r, const cv::Scalar& c) {
    cv::circle(img_, p(u, v), flen(r), c, cv::FILLED, cv::LINE_AA, kShift);
  }
  void ring(double u, double v, double r, double thickness, const cv::Scalar& c) {
    cv::circle(img_, p(u, v), flen(r), c, len(thickness), cv::LINE_AA, kShift);
  }
  // A thick polyline with round joints.
  void stroke(std::initializer_list<std::pair<double, double>> pts, double thickness,
              const cv::Scalar& c) {
    const std::vector<std::pair<double, double>> v(pts);
    for (std::size_t i = 0; i + 1 < v.size(); ++i) {
      cv::line(img_, p(v[i].first, v[i].second), p(v[i + 1].first, v[i + 1].second), c,
               len(thickness), cv::LINE_AA, kShift);
    }
    for (const auto& [u, w] : v) disc(u, w, thickness / 2, c);
  }
  void arc(double u, double v, double r, double from_deg, double to_deg, double thickness,
           const cv::Scalar& c) {
    cv::ellipse(img_, p(u, v), cv::Size(flen(r), flen(r)), 0, from_deg, to_deg, c, len(thickness),
                cv::LINE_AA, kShift);
  }

 private:
  static constexpr int kShift = 4;
  static constexpr double kScale = 1 << kShift;
  cv::Mat& img_;
  double x0_ = 0, y0_ = 0;
  int side_ = 1;
};

// An arrow through the centre pointing at `angle` degrees (0 = right,
// 90 = up), shaft and head.
void arrow(Pen& pen, double angle_deg, const cv::Scalar& c) {
  const double a = angle_deg * CV_PI / 180.0, ca = std::cos(a), sa = -std::sin(a);
  const auto at = [&](double x, double y) {  // x along the arrow, y across, from the centre
    return std::pair<double, double>{0.5 + x * ca - y * sa, 0.5 + x * sa + y * ca};
  };
  const auto [t0u, t0v] = at(-0.42, -0.09);
  const auto [t1u, t1v] = at(0.08, -0.09);
  const auto [t2u, t2v] = at(0.08, 0.09);
  const auto [t3u, t3v] = at(-0.42, 0.09);
  pen.poly({{t0u, t0v}, {t1u, t1v}, {t2u, t2v}, {t3u, t3v}}, c);
  const auto [h0u, h0v] = at(0.02, -0.3);
  const auto [h1u, h1v] = at(0.44, 0.0);
  const auto [h2u, h2v] = at(0.02, 0.3);
  pen.poly({{h0u, h0v}, {h1u, h1v}, {h2u, h2v}}, c);
}

void person(Pen& pen, bool woman, const cv::Scalar& c) {
  pen.disc(0.5, 0.12, 0.085, c);
  if (woman) {
    pen.poly({{0.41, 0.24}, {0.59, 0.24}, {0.76, 0.68}, {0.24, 0.68}}, c);
    pen.rect(0.40, 0.66, 0.47, 0.95, c);
    pen.rect(0.53, 0.66, 0.60, 0.95, c);
  } else {
    pen.poly({{0.37, 0.24}, {0.63, 0.24}, {0.63, 0.58}, {0.37, 0.58}}, c);
    pen.rect(0.38, 0.56, 0.48, 0.95, c);
    pen.rect(0.52, 0.56, 0.62, 0.95, c);
  }
  pen.stroke({{0.35, 0.28}, {0.27, 0.55}}, 0.075, c);
  pen.stroke({{0.65, 0.28}, {0.73, 0.55}}, 0.075, c);
}

void warning_triangle(Pen& pen) {
  pen.poly({{0.5, 0.05}, {0.96, 0.9}, {0.04, 0.9}}, kBlack);
  pen.poly({{0.5, 0.17}, {0.86, 0.84}, {0.14, 0.84}}, kYellow);
}

void prohibition(Pen& pen) {
  pen.ring(0.5, 0.5, 0.42, 0.08, kRed);
  pen.stroke({{0.21, 0.21}, {0.79, 0.79}}, 0.08, kRed);
}

}  // namespace

const char* pictogram_name(Pictogram p) {
  static const char* const names[] = {
      "man",         "woman",          "running-man", "door",           "arrow-right",
      "arrow-left",  "arrow-up",       "arrow-down",  "arrow-up-right", "stairs-up",
      "stairs-down", "extinguisher",   "no-smoking",  "wheelchair",     "lift",
      "first-aid",   "info",           "no-entry",    "warning",        "high-voltage",
      "flame",       "drinking-water", "cup",         "wifi",           "no-phones",
      "camera",      "assembly",       "bell",        "parking",        "wet-floor"};
  const auto i = static_cast<std::size_t>(p);
  return i < sizeof(names) / sizeof(names[0]) ? names[i] : "unknown";
}

void draw_pictogram(cv::Mat& img, Pictogram p, const cv::Rect& box, const cv::Scalar& fg,
                    const cv::Scalar& bg) {
  Pen pen(img, box);
  switch (p) {
    case Pictogram::kMan:
    case Pictogram::kWoman:
      person(pen, p == Pictogram::kWoman, fg);
      break;
    case Pictogram::kRunningMan:
      pen.disc(0.63, 0.12, 0.085, fg);
      pen.stroke({{0.58, 0.26}, {0.46, 0.55}}, 0.13, fg);
      pen.stroke({{0.58, 0.31}, {0.72, 0.42}, {0.84, 0.33}}, 0.075, fg);
      pen.stroke({{0.53, 0.31}, {0.38, 0.33}, {0.27, 0.46}}, 0.075, fg);
      pen.stroke({{0.47, 0.56}, {0.63, 0.71}, {0.60, 0.93}}, 0.085, fg);
      pen.stroke({{0.44, 0.58}, {0.33, 0.76}, {0.14, 0.79}}, 0.085, fg);
      break;
    case Pictogram::kDoor:
      pen.rect(0.18, 0.04, 0.82, 0.96, fg);
      pen.rect(0.27, 0.12, 0.73, 0.96, bg);
      pen.disc(0.65, 0.55, 0.04, fg);
      break;
    case Pictogram::kArrowRight:
      arrow(pen, 0, fg);
      break;
    case Pictogram::kArrowLeft:
      arrow(pen, 180, fg);
      break;
    case Pictogram::kArrowUp:
      arrow(pen, 90, fg);
      break;
    case Pictogram::kArrowDown:
      arrow(pen, 270, fg);
      break;
    case Pictogram::kArrowUpRight:
      arrow(pen, 45, fg);
      break;
    case Pictogram::kStairsUp:
    case Pictogram::kStairsDown: {
      const bool up = p == Pictogram::kStairsUp;
      pen.poly({{0.08, 0.92},
                {0.08, 0.76},
                {0.29, 0.76},
                {0.29, 0.6},
                {0.5, 0.6},
                {0.5, 0.44},
                {0.71, 0.44},
                {0.71, 0.28},
                {0.92, 0.28},
                {0.92, 0.92}},
               fg);
      if (up) {
        pen.stroke({{0.12, 0.5}, {0.36, 0.26}}, 0.06, fg);
        pen.poly({{0.42, 0.14}, {0.44, 0.36}, {0.22, 0.2}}, fg);
      } else {
        pen.stroke({{0.42, 0.18}, {0.2, 0.4}}, 0.06, fg);
        pen.poly({{0.1, 0.52}, {0.12, 0.3}, {0.32, 0.5}}, fg);
      }
      break;
    }
    case Pictogram::kExtinguisher:
      pen.rect(0.36, 0.36, 0.64, 0.93, fg);
      pen.disc(0.5, 0.37, 0.14, fg);
      pen.rect(0.45, 0.14, 0.55, 0.26, fg);
      pen.stroke({{0.40, 0.15}, {0.64, 0.09}}, 0.045, fg);
      pen.stroke({{0.55, 0.19}, {0.76, 0.24}, {0.83, 0.44}, {0.78, 0.70}}, 0.035, fg);
      pen.rect(0.39, 0.52, 0.61, 0.64, bg);
      break;
    case Pictogram::kNoSmoking:
      pen.rect(0.17, 0.50, 0.66, 0.60, fg);
      pen.rect(0.68, 0.50, 0.80, 0.60, fg);
      pen.stroke({{0.74, 0.45}, {0.70, 0.36}, {0.76, 0.28}, {0.72, 0.2}}, 0.03, fg);
      prohibition(pen);
      break;
    case Pictogram::kWheelchair:
      pen.disc(0.44, 0.12, 0.08, fg);
      pen.stroke({{0.42, 0.25}, {0.42, 0.55}, {0.66, 0.55}, {0.74, 0.84}}, 0.08, fg);
      pen.stroke({{0.42, 0.36}, {0.62, 0.38}}, 0.06, fg);
      pen.arc(0.42, 0.68, 0.23, 100, 390, 0.055, fg);
      break;
    case Pictogram::kLift:
      pen.rect(0.12, 0.04, 0.88, 0.96, fg);
      pen.rect(0.17, 0.09, 0.83, 0.91, bg);
      pen.rect(0.22, 0.36, 0.48, 0.86, fg);
      pen.rect(0.52, 0.36, 0.78, 0.86, fg);
      pen.poly({{0.27, 0.29}, {0.36, 0.13}, {0.45, 0.29}}, fg);
      pen.poly({{0.55, 0.13}, {0.73, 0.13}, {0.64, 0.29}}, fg);
      break;
    case Pictogram::kFirstAid:
      pen.rect(0.37, 0.1, 0.63, 0.9, fg);
      pen.rect(0.1, 0.37, 0.9, 0.63, fg);
      break;
    case Pictogram::kInfo:
      pen.ring(0.5, 0.5, 0.44, 0.06, fg);
      pen.disc(0.5, 0.27, 0.07, fg);
      pen.rect(0.43, 0.40, 0.57, 0.76, fg);
      pen.rect(0.36, 0.72, 0.64, 0.79, fg);
      pen.rect(0.38, 0.40, 0.50, 0.45, fg);
      break;
    case Pictogram::kNoEntry:
      pen.disc(0.5, 0.5, 0.46, kRed);
      pen.rect(0.15, 0.41, 0.85, 0.59, kWhite);
      break;
    case Pictogram::kWarning:
      warning_triangle(pen);
      pen.poly({{0.455, 0.34}, {0.545, 0.34}, {0.53, 0.66}, {0.47, 0.66}}, kBlack);
      pen.disc(0.5, 0.75, 0.045, kBlack);
      break;
    case Pictogram::kHighVoltage:
      warning_triangle(pen);
      pen.poly({{0.56, 0.3},
                {0.38, 0.6},
                {0.5, 0.6},
                {0.42, 0.82},
                {0.66, 0.5},
                {0.53, 0.5},
                {0.62, 0.3}},
               kBlack);
      break;
    case Pictogram::kFlame:
      pen.poly({{0.5, 0.04},
                {0.66, 0.28},
                {0.77, 0.55},
                {0.71, 0.8},
                {0.5, 0.94},
                {0.29, 0.8},
                {0.23, 0.56},
                {0.36, 0.34},
                {0.44, 0.46}},
               fg);
      pen.poly({{0.52, 0.42}, {0.62, 0.62}, {0.6, 0.8}, {0.5, 0.86}, {0.4, 0.8}, {0.4, 0.66}}, bg);
      break;
    case Pictogram::kDrinkingWater:
      pen.rect(0.12, 0.2, 0.62, 0.3, fg);
      pen.rect(0.52, 0.3, 0.62, 0.42, fg);
      pen.rect(0.3, 0.1, 0.36, 0.2, fg);
      pen.rect(0.2, 0.07, 0.46, 0.12, fg);
      pen.disc(0.57, 0.74, 0.13, fg);
      pen.poly({{0.57, 0.48}, {0.45, 0.7}, {0.69, 0.7}}, fg);
      break;
    case Pictogram::kCup:
      pen.poly({{0.18, 0.42}, {0.7, 0.42}, {0.64, 0.88}, {0.24, 0.88}}, fg);
      pen.ring(0.72, 0.58, 0.11, 0.045, fg);
      pen.stroke({{0.34, 0.34}, {0.3, 0.24}, {0.35, 0.13}}, 0.035, fg);
      pen.stroke({{0.5, 0.34}, {0.46, 0.24}, {0.51, 0.13}}, 0.035, fg);
      break;
    case Pictogram::kWifi:
      for (const double r : {0.2, 0.4, 0.6}) pen.arc(0.5, 0.82, r, 225, 315, 0.075, fg);
      pen.disc(0.5, 0.82, 0.07, fg);
      break;
    case Pictogram::kNoPhones:
      pen.rect(0.36, 0.16, 0.64, 0.84, fg);
      pen.rect(0.40, 0.24, 0.60, 0.68, bg);
      pen.disc(0.5, 0.76, 0.035, bg);
      prohibition(pen);
      break;
    case Pictogram::kCamera:
      pen.poly({{0.12, 0.28}, {0.7, 0.42}, {0.65, 0.6}, {0.07, 0.46}}, fg);
      pen.poly({{0.7, 0.44}, {0.82, 0.4}, {0.8, 0.6}, {0.67, 0.57}}, fg);
      pen.stroke({{0.42, 0.55}, {0.48, 0.78}, {0.86, 0.78}}, 0.05, fg);
      pen.rect(0.84, 0.62, 0.92, 0.94, fg);
      break;
    case Pictogram::kAssembly:
      for (int i = 0; i < 4; ++i) {
        const double sx = (i % 2) ? 1.0 : -1.0, sy = (i / 2) ? 1.0 : -1.0;
        pen.stroke({{0.5 + sx * 0.44, 0.5 + sy * 0.44}, {0.5 + sx * 0.27, 0.5 + sy * 0.27}}, 0.06,
                   fg);
        pen.poly({{0.5 + sx * 0.2, 0.5 + sy * 0.2},
                  {0.5 + sx * 0.36, 0.5 + sy * 0.2},
                  {0.5 + sx * 0.2, 0.5 + sy * 0.36}},
                 fg);
      }
      for (const double u : {0.38, 0.5, 0.62}) {
        pen.disc(u, 0.42, 0.045, fg);
        pen.rect(u - 0.04, 0.49, u + 0.04, 0.62, fg);
      }
      break;
    case Pictogram::kBell:
      pen.disc(0.5, 0.42, 0.25, fg);
      pen.rect(0.25, 0.42, 0.75, 0.72, fg);
      pen.rect(0.13, 0.7, 0.87, 0.79, fg);
      pen.disc(0.5, 0.86, 0.065, fg);
      pen.disc(0.5, 0.14, 0.05, fg);
      break;
    case Pictogram::kParking: {
      pen.rect(0.08, 0.08, 0.92, 0.92, fg);
      pen.rect(0.14, 0.14, 0.86, 0.86, bg);
      pen.rect(0.3, 0.2, 0.42, 0.8, fg);
      pen.disc(0.52, 0.38, 0.18, fg);
      pen.rect(0.36, 0.2, 0.52, 0.56, fg);
      pen.disc(0.52, 0.38, 0.07, bg);
      pen.rect(0.42, 0.31, 0.52, 0.45, bg);
      break;
    }
    case Pictogram::kWetFloor:
      warning_triangle(pen);
      pen.disc(0.62, 0.4, 0.055, kBlack);
      pen.stroke({{0.59, 0.48}, {0.47, 0.64}}, 0.06, kBlack);
      pen.stroke({{0.47, 0.64}, {0.62, 0.76}}, 0.045, kBlack);
      pen.stroke({{0.47, 0.64}, {0.32, 0.73}}, 0.045, kBlack);
      pen.stroke({{0.56, 0.52}, {0.68, 0.56}}, 0.04, kBlack);
      pen.stroke({{0.54, 0.53}, {0.42, 0.48}}, 0.04, kBlack);
      pen.rect(0.22, 0.79, 0.78, 0.81, kBlack);
      break;
    case Pictogram::kCount:
      break;
  }
}

}  // namespace kg
