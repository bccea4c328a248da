// The plain-text ground truth of the photo sets, read strictly and within
// bounds (docs/EVAL.md): exit-signs' corners.txt, planar-pairs'
// NAME_H_A_to_B.txt and the Oxford set's H1toNp. The files are regular
// files (platform/files/regular_file.h: a FIFO or /dev/zero is refused, not
// read) of bounded size. OpenCV-free: the fuzz targets compile it in.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include "keygraph/status.h"
#include "keygraph/types.h"

namespace kg {

inline constexpr std::size_t kMaxCornersFileBytes = std::size_t{16} << 20;
inline constexpr std::size_t kMaxCornersLineBytes = 4096;
inline constexpr std::size_t kMaxHomographyFileBytes = std::size_t{64} << 10;

// One sign of corners.txt: "IMAGE INDEX X1 Y1 X2 Y2 X3 Y3 X4 Y4".
struct MarkedSign {
  std::string image;    // relative to the set's directory
  int index = 0;        // the sign's number in its image, 0..1000000
  double corners[8]{};  // x1 y1 ... x4 y4 as written
};

// corners.txt's text: blank lines skipped; every other line exactly the
// ten fields above, the image without control characters, the corners
// finite numbers within 1e7 forming a simple quadrilateral
// (quad_geometry.h). Errors are "PATH:LINE: what".
Status parse_corners_text(std::string_view text, const std::string& path,
                          std::vector<MarkedSign>& out);
// The file, then parse_corners_text(); an empty result is an error.
Status read_corners_file(const std::string& path, std::vector<MarkedSign>& out);

// A homography file's text: exactly 9 finite numbers separated by
// whitespace (row-major), invertible. Errors name `path`.
Status parse_homography_text(std::string_view text, const std::string& path, Homography& h);
Status read_homography_file(const std::string& path, Homography& h);

}  // namespace kg
