#include "eval/report_io.h"

#include <cmath>
#include <cstdio>
#include <filesystem>

#include <opencv2/imgcodecs.hpp>

#include "platform/files/output_file.h"

namespace kg {

std::string json_quote(std::string_view s) {
  std::string out = "\"";
  for (const char ch : s) {
    const auto c = static_cast<unsigned char>(ch);
    if (c == '"' || c == '\\') {
      out += '\\';
      out += ch;
    } else if (c < 0x20 || c == 0x7f) {
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

Status write_text_file(const std::string& path, const std::string& text,
                       const std::vector<std::string>& inputs) {
  platform::OutputFile out;
  Status s = out.create(path, inputs);
  if (s) s = out.write(text.data(), text.size());
  if (s) s = out.commit();
  return s;
}

Status encode_png(const cv::Mat& image, const std::string& path, std::vector<std::uint8_t>& png) {
  bool ok = false;
  try {
    ok = !image.empty() && cv::imencode(".png", image, png, {cv::IMWRITE_PNG_COMPRESSION, 9});
  } catch (const cv::Exception&) {
    ok = false;
  }
  if (!ok) return {StatusCode::kIoError, path + ": cannot encode the picture as PNG"};
  return Status::ok();
}

Status add_png(platform::OutputSet& out, const std::string& path, const cv::Mat& image) {
  std::vector<std::uint8_t> png;
  if (Status s = encode_png(image, path, png); !s) return s;
  return out.add(path, png.data(), png.size());
}

std::vector<std::string> files_under(const std::string& dir, int depth) {
  namespace fs = std::filesystem;
  std::vector<std::string> out;
  if (dir.empty() || depth < 1) return out;
  std::error_code ec;
  for (const fs::directory_entry& e : fs::directory_iterator(dir, ec)) {
    if (e.is_regular_file(ec)) {
      out.push_back(e.path().string());
    } else if (e.is_directory(ec)) {
      for (std::string& f : files_under(e.path().string(), depth - 1)) out.push_back(std::move(f));
    }
  }
  return out;
}

}  // namespace kg
