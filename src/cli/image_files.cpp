// Image files for the desktop commands, through OpenCV (build/image_io.h).
#include <cstdio>
#include <filesystem>
#include <string>
#include <system_error>

#include <opencv2/imgcodecs.hpp>

#if defined(__unix__) || defined(__APPLE__)
#include <unistd.h>
#endif

#include "build/image_io.h"
#include "cli/commands.h"

namespace kg::cli {

Status load_image(const std::string& path, cv::Mat& gray) {
#if defined(__unix__) || defined(__APPLE__)
  // Decoders (libpng, libjpeg) print their own complaints on stderr. Hold
  // them in a temporary file: on failure our one line replaces them, on
  // success they are passed on (e.g. libpng's sRGB profile warnings).
  std::FILE* held = std::tmpfile();
  std::fflush(stderr);
  const int saved = held != nullptr ? ::dup(2) : -1;
  if (saved < 0 || ::dup2(::fileno(held), 2) < 0) {
    if (saved >= 0) ::close(saved);
    if (held != nullptr) std::fclose(held);
    return load_gray(path, gray);
  }
  Status s = load_gray(path, gray);
  std::fflush(stderr);
  ::dup2(saved, 2);
  ::close(saved);
  if (s) {
    std::rewind(held);
    char buf[4096];
    for (std::size_t n; (n = std::fread(buf, 1, sizeof(buf), held)) > 0;)
      std::fwrite(buf, 1, n, stderr);
  }
  std::fclose(held);
  return s;
#else
  return load_gray(path, gray);
#endif
}

bool write_image_atomically(const std::string& path, const cv::Mat& image, std::string& error) {
  const std::filesystem::path target(path);
  std::string ext = target.extension().string();
  if (ext.empty()) {
    error = path + ": output image needs an extension such as .png";
    return false;
  }
  // Temporary name keeps the extension so the encoder is chosen from it.
  const std::string tmp = (target.parent_path() / (".tmp-" + target.filename().string())).string();
  bool ok = false;
  try {
    ok = cv::imwrite(tmp, image);
  } catch (const cv::Exception&) {
    ok = false;
  }
  std::error_code ec;
  if (!ok) {
    std::filesystem::remove(tmp, ec);
    error = "cannot write image " + path;
    return false;
  }
  std::filesystem::rename(tmp, target, ec);
  if (ec) {
    std::filesystem::remove(tmp, ec);
    error = "cannot write image " + path;
    return false;
  }
  return true;
}

}  // namespace kg::cli
