#include "eval/report_io.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <system_error>
#include <vector>

#include <opencv2/imgcodecs.hpp>

namespace kg {

std::string json_quote(std::string_view s) {
  std::string out = "\"";
  for (const char ch : s) {
    const auto c = static_cast<unsigned char>(ch);
    if (c == '"' || c == '\\') {
      out += '\\';
      out += ch;
    } else if (c < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof(buf), "\\u%04x", c);
      out += buf;
    } else {
      out += ch;
    }
  }
  return out + "\"";
}

std::string json_value(double v) {
  if (!std::isfinite(v)) return "null";
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.10g", v);
  return buf;
}

Status write_text_file(const std::string& path, const std::string& text) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary);
    out << text;
    out.flush();
    if (!out) {
      std::error_code ec;
      std::filesystem::remove(tmp, ec);
      return {StatusCode::kIoError, "cannot write " + path};
    }
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::filesystem::remove(tmp, ec);
    return {StatusCode::kIoError, "cannot write " + path};
  }
  return Status::ok();
}

Status write_png_file(const std::string& path, const cv::Mat& image) {
  std::vector<std::uint8_t> bytes;
  bool ok = false;
  try {
    ok = !image.empty() && cv::imencode(".png", image, bytes, {cv::IMWRITE_PNG_COMPRESSION, 9});
  } catch (const cv::Exception&) {
    ok = false;
  }
  if (!ok) return {StatusCode::kIoError, "cannot encode " + path};
  return write_text_file(path, std::string(bytes.begin(), bytes.end()));
}

Status ensure_directory(const std::string& path) {
  std::error_code ec;
  std::filesystem::create_directories(path, ec);
  if (ec || !std::filesystem::is_directory(path, ec))
    return {StatusCode::kIoError, "cannot create directory " + path};
  return Status::ok();
}

}  // namespace kg
