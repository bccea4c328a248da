#include "eval/set_files.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "builder/strict_json.h"
#include "eval/quad_geometry.h"
#include "platform/files/regular_file.h"

namespace kg {

namespace {

constexpr std::string_view kSpace = " \t\r\f\v";

// The whitespace-separated words of `text` (newlines separate them too
// when `across_lines`), at most `max` + 1 of them (the one more tells of
// extra words without reading them all).
std::vector<std::string_view> words(std::string_view text, bool across_lines, std::size_t max) {
  const std::string_view space = across_lines ? std::string_view(" \t\r\f\v\n") : kSpace;
  std::vector<std::string_view> out;
  std::size_t i = 0;
  while (out.size() <= max) {
    i = text.find_first_not_of(space, i);
    if (i == std::string_view::npos) break;
    const std::size_t end = std::min(text.find_first_of(space, i), text.size());
    out.push_back(text.substr(i, end - i));
    i = end;
  }
  return out;
}

// A whole word as a finite number.
bool to_number(std::string_view word, double& out) {
  if (word.empty() || word.size() > 64) return false;
  const std::string copy(word);
  char* end = nullptr;
  out = std::strtod(copy.c_str(), &end);
  // (an underflow to a subnormal is a number; an overflow is not: not finite)
  return end == copy.c_str() + copy.size() && std::isfinite(out);
}

}  // namespace

Status parse_corners_text(std::string_view text, const std::string& path,
                          std::vector<MarkedSign>& out) {
  out.clear();
  std::size_t begin = 0;
  for (int number = 1; begin < text.size(); ++number) {
    std::size_t end = text.find('\n', begin);
    if (end == std::string_view::npos) end = text.size();
    const std::string_view line = text.substr(begin, end - begin);
    begin = end + 1;
    const auto bad = [&](const std::string& what) {
      return Status{StatusCode::kCorruptData, path + ":" + std::to_string(number) + ": " + what};
    };
    if (line.size() > kMaxCornersLineBytes)
      return bad("line of " + std::to_string(line.size()) + " bytes, over the " +
                 std::to_string(kMaxCornersLineBytes) + " a line may have");
    const std::vector<std::string_view> w = words(line, false, 10);
    if (w.empty()) continue;
    MarkedSign sign;
    double v[9];
    bool ok = w.size() == 10 && !has_control_character(w[0]);
    for (std::size_t i = 1; ok && i < 10; ++i) ok = to_number(w[i], v[i - 1]);
    ok = ok && v[0] >= 0 && v[0] <= 1000000 && v[0] == std::floor(v[0]);
    for (int i = 1; ok && i < 9; ++i) ok = std::abs(v[i]) <= 1e7;
    if (!ok) return bad("expected 'image index x1 y1 x2 y2 x3 y3 x4 y4'");
    sign.image = std::string(w[0]);
    sign.index = static_cast<int>(v[0]);
    Point2f quad[4];
    for (int c = 0; c < 4; ++c) {
      sign.corners[2 * c] = v[1 + 2 * c];
      sign.corners[2 * c + 1] = v[2 + 2 * c];
      quad[c] = {static_cast<float>(v[1 + 2 * c]), static_cast<float>(v[2 + 2 * c])};
    }
    if (!is_simple_quad(quad))
      return bad("the corners cross or have no area: give them around the outline");
    out.push_back(std::move(sign));
  }
  return Status::ok();
}

Status read_corners_file(const std::string& path, std::vector<MarkedSign>& out) {
  std::string text;
  if (Status s = platform::read_text_file(path, text, kMaxCornersFileBytes, "a corners.txt"); !s)
    return s;
  if (Status s = parse_corners_text(text, path, out); !s) return s;
  if (out.empty()) return {StatusCode::kCorruptData, path + ": no signs in the file"};
  return Status::ok();
}

Status parse_homography_text(std::string_view text, const std::string& path, Homography& h) {
  const std::vector<std::string_view> w = words(text, true, 9);
  bool ok = w.size() == 9;
  for (std::size_t i = 0; ok && i < 9; ++i) ok = to_number(w[i], h[i]);
  if (!ok)
    return {StatusCode::kCorruptData,
            path + ": expected 9 numbers (a 3x3 homography, row-major), and nothing else"};
  Homography normalised = h;
  if (!normalise_homography(normalised))
    return {StatusCode::kCorruptData,
            path + ": the homography is singular or does not normalise to h33 = 1"};
  return Status::ok();
}

Status read_homography_file(const std::string& path, Homography& h) {
  std::string text;
  if (Status s = platform::read_text_file(path, text, kMaxHomographyFileBytes, "a homography file");
      !s)
    return s;
  return parse_homography_text(text, path, h);
}

}  // namespace kg
