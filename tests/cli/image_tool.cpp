// Test input and checks for the CLI's pictures (cli_conventions.sh):
//   kg_image_tool scale IN OUT FACTOR [--turn]
//       IN (any image OpenCV reads, in colour) scaled by FACTOR, turned
//       upside down with --turn, written to OUT in the format its extension
//       names: model photos over the pixel limit, objects upside down.
//   kg_image_tool colour IMAGE
//       prints the percentage of IMAGE's pixels whose channels differ by
//       more than 40 (0 for a gray picture).
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <string>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace {

int usage() {
  std::fprintf(stderr,
               "usage: kg_image_tool scale IN OUT FACTOR [--turn]\n"
               "       kg_image_tool colour IMAGE\n");
  return 2;
}

int scale(int argc, char** argv) {
  if (argc < 5 || argc > 6 || (argc == 6 && std::string(argv[5]) != "--turn")) return usage();
  const double factor = std::atof(argv[4]);
  const cv::Mat in = cv::imread(argv[2], cv::IMREAD_COLOR);
  if (in.empty() || !(factor > 0 && factor <= 64)) {
    std::fprintf(stderr, "kg_image_tool: cannot read %s, or bad factor %s\n", argv[2], argv[4]);
    return 1;
  }
  cv::Mat out;
  cv::resize(in, out, cv::Size(), factor, factor, factor > 1 ? cv::INTER_CUBIC : cv::INTER_AREA);
  if (argc == 6) cv::rotate(out, out, cv::ROTATE_180);
  if (!cv::imwrite(argv[3], out)) {
    std::fprintf(stderr, "kg_image_tool: cannot write %s\n", argv[3]);
    return 1;
  }
  return 0;
}

int colour(int argc, char** argv) {
  if (argc != 3) return usage();
  const cv::Mat in = cv::imread(argv[2], cv::IMREAD_COLOR);
  if (in.empty()) {
    std::fprintf(stderr, "kg_image_tool: cannot read %s\n", argv[2]);
    return 1;
  }
  long coloured = 0;
  for (int y = 0; y < in.rows; ++y) {
    for (int x = 0; x < in.cols; ++x) {
      const cv::Vec3b p = in.at<cv::Vec3b>(y, x);
      const int lo = std::min({p[0], p[1], p[2]}), hi = std::max({p[0], p[1], p[2]});
      if (hi - lo > 40) ++coloured;
    }
  }
  std::printf("%.1f\n", 100.0 * static_cast<double>(coloured) / static_cast<double>(in.total()));
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) return usage();
  const std::string command = argv[1];
  if (command == "scale") return scale(argc, argv);
  if (command == "colour") return colour(argc, argv);
  return usage();
}
