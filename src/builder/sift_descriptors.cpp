#include "builder/sift_descriptors.h"

#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>

namespace kg {

namespace {

// OpenCV's SIFT pyramid: 3 layers per octave plus 3 (blur increments of
// 2^(1/3) from sigma 1.6), the input assumed blurred by 0.5, no upsampling
// (provided keypoints start at octave 0), each octave halving the previous
// octave's layer 3 by taking every other pixel.
constexpr int kOctaveLayers = 3;
constexpr int kLayers = kOctaveLayers + 3;
constexpr double kSigma = 1.6;
constexpr double kInitSigma = 0.5;
// Orientation histogram (SIFT_ORI_*): 36 bins, Gaussian window of 1.5
// scales, radius 3 window sigmas.
constexpr int kBins = 36;
constexpr float kWindowFactor = 1.5f;
constexpr float kRadiusFactor = 3.f * kWindowFactor;

// Octaves OpenCV builds by default for an image of this size, less one, so
// the coarsest level used keeps at least ~8 pixels a side.
int max_octave(const cv::Mat& gray) {
  const int n =
      cvRound(std::log(static_cast<double>(std::min(gray.cols, gray.rows))) / std::log(2.0)) - 2;
  return std::max(0, n - 2);
}

void build_pyramid(const cv::Mat& gray, int octaves, std::vector<cv::Mat>& pyramid) {
  double sig[kLayers];
  sig[0] = kSigma;
  const double k = std::pow(2.0, 1.0 / kOctaveLayers);
  for (int i = 1; i < kLayers; ++i) {
    const double prev = std::pow(k, i - 1) * kSigma, total = prev * k;
    sig[i] = std::sqrt(total * total - prev * prev);
  }
  pyramid.resize(static_cast<std::size_t>(octaves * kLayers));
  cv::Mat base;
  gray.convertTo(base, CV_32F);
  const double first = std::sqrt(std::max(kSigma * kSigma - kInitSigma * kInitSigma, 0.01));
  for (int o = 0; o < octaves; ++o) {
    for (int i = 0; i < kLayers; ++i) {
      cv::Mat& dst = pyramid[static_cast<std::size_t>(o * kLayers + i)];
      if (o == 0 && i == 0) {
        cv::GaussianBlur(base, dst, cv::Size(), first, first);
      } else if (i == 0) {
        const cv::Mat& src = pyramid[static_cast<std::size_t>((o - 1) * kLayers + kOctaveLayers)];
        cv::resize(src, dst, cv::Size(src.cols / 2, src.rows / 2), 0, 0, cv::INTER_NEAREST);
      } else {
        cv::GaussianBlur(pyramid[static_cast<std::size_t>(o * kLayers + i - 1)], dst, cv::Size(),
                         sig[i], sig[i]);
      }
    }
  }
}

// Dominant gradient orientation (degrees, counter-clockwise with y up, as
// SIFT's) in a Gaussian window of sigma `scale` * 1.5 around `centre`.
float dominant_orientation(const cv::Mat& img, cv::Point centre, float scale) {
  const int radius = cvRound(kRadiusFactor * scale);
  const float window = kWindowFactor * scale;
  const float exp_scale = -1.f / (2.f * window * window);
  float hist[kBins] = {};
  for (int i = -radius; i <= radius; ++i) {
    const int y = centre.y + i;
    if (y <= 0 || y >= img.rows - 1) continue;
    const float* row = img.ptr<float>(y);
    const float* up = img.ptr<float>(y - 1);
    const float* down = img.ptr<float>(y + 1);
    for (int j = -radius; j <= radius; ++j) {
      const int x = centre.x + j;
      if (x <= 0 || x >= img.cols - 1) continue;
      const float dx = row[x + 1] - row[x - 1];
      const float dy = up[x] - down[x];
      const float w = std::exp(static_cast<float>(i * i + j * j) * exp_scale);
      float angle = std::atan2(dy, dx) * static_cast<float>(180.0 / CV_PI);
      if (angle < 0.f) angle += 360.f;
      int bin = cvRound(angle * (kBins / 360.f));
      if (bin >= kBins) bin -= kBins;
      hist[bin] += w * std::sqrt(dx * dx + dy * dy);
    }
  }
  // Smoothing as SIFT's: circular [1 4 6 4 1] / 16.
  float smooth[kBins];
  for (int b = 0; b < kBins; ++b) {
    auto at = [&](int d) { return hist[(b + d + kBins) % kBins]; };
    smooth[b] =
        (at(-2) + at(2)) * (1.f / 16.f) + (at(-1) + at(1)) * (4.f / 16.f) + at(0) * (6.f / 16.f);
  }
  int peak = 0;
  for (int b = 1; b < kBins; ++b) {
    if (smooth[b] > smooth[peak]) peak = b;
  }
  if (!(smooth[peak] > 0.f)) return 0.f;
  const float l = smooth[(peak + kBins - 1) % kBins], r = smooth[(peak + 1) % kBins];
  const float denom = l - 2.f * smooth[peak] + r;
  float bin = static_cast<float>(peak) + (denom != 0.f ? 0.5f * (l - r) / denom : 0.f);
  if (bin < 0.f) bin += kBins;
  if (bin >= kBins) bin -= kBins;
  return bin * (360.f / kBins);
}

}  // namespace

SiftDescriber::SiftDescriber()
    : sift_(cv::SIFT::create(0, kOctaveLayers, 0.04, 10, kSigma, CV_8U)) {}

void SiftDescriber::describe(const cv::Mat& gray, const Keypoint* keypoints, int count,
                             std::vector<std::uint8_t>& out) {
  constexpr auto kRow = static_cast<std::size_t>(kVertexDescriptorSize);
  out.assign(static_cast<std::size_t>(std::max(0, count)) * kRow, 0);
  if (count <= 0 || gray.empty()) return;
  // Pyramid level per keypoint: the layer whose blur is nearest the
  // keypoint's sigma, in the smallest octave holding it (layers 1..3, as
  // SIFT detects; sigmas below 1.6 use the input octave's layer 0).
  const int top = max_octave(gray);
  cv_keypoints_.resize(static_cast<std::size_t>(count));
  int octaves = 1;
  for (int i = 0; i < count; ++i) {
    const Keypoint& k = keypoints[i];
    const float sigma = k.scale > 0.f ? k.scale : kSiftDefaultSigma;
    const int level =
        std::max(0, static_cast<int>(std::lround(kOctaveLayers * std::log2(sigma / kSigma))));
    const int octave = std::min(level <= 0 ? 0 : (level - 1) / kOctaveLayers, top);
    const int layer = std::min(level - octave * kOctaveLayers, kLayers - 1);
    octaves = std::max(octaves, octave + 1);
    cv::KeyPoint& c = cv_keypoints_[static_cast<std::size_t>(i)];
    c.pt = cv::Point2f(k.x, k.y);
    c.size = 2.f * sigma;
    c.octave = octave | (layer << 8);
    c.response = k.response;
    c.class_id = i;
  }
  build_pyramid(gray, octaves, pyramid_);
  for (cv::KeyPoint& c : cv_keypoints_) {
    const int octave = c.octave & 255, layer = (c.octave >> 8) & 255;
    const float to_octave = 1.f / static_cast<float>(1 << octave);
    const cv::Mat& img = pyramid_[static_cast<std::size_t>(octave * kLayers + layer)];
    const float orientation = dominant_orientation(
        img, cv::Point(cvRound(c.pt.x * to_octave), cvRound(c.pt.y * to_octave)),
        0.5f * c.size * to_octave);
    // cv::KeyPoint angle convention (clockwise, y down); OpenCV's SIFT
    // rotates its descriptor window by 360 - angle.
    c.angle = 360.f - orientation;
    if (std::abs(c.angle - 360.f) < 1e-4f) c.angle = 0.f;
  }
  sift_->compute(gray, cv_keypoints_, descriptors_);
  if (descriptors_.rows != count || descriptors_.cols != kVertexDescriptorSize ||
      descriptors_.type() != CV_8U)
    return;  // never happens with provided keypoints; rows stay zero (dissimilar)
  for (int i = 0; i < count; ++i) {
    const int src = cv_keypoints_[static_cast<std::size_t>(i)].class_id;
    std::copy_n(descriptors_.ptr<std::uint8_t>(i), kRow,
                out.data() + static_cast<std::size_t>(src) * kRow);
  }
}

}  // namespace kg
