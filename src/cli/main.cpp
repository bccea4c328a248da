// keygraph: build model indexes and detect models in images.
#include <cstdio>
#include <exception>
#include <filesystem>
#include <iostream>
#include <string>
#include <system_error>

#include <opencv2/imgcodecs.hpp>

#if defined(__unix__) || defined(__APPLE__)
#include <unistd.h>
#endif

#include "build/image_io.h"
#include "cli/commands.h"

namespace kg::cli {

int fail(const std::string& message) {
  std::fprintf(stderr, "keygraph: %s\n", message.c_str());
  return 1;
}

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

namespace {

void usage(std::FILE* out) {
  std::fprintf(
      out,
      "usage: keygraph <command> [options]\n"
      "\n"
      "commands:\n"
      "  build [--name NAME]... [--roi X,Y,W,H] [--detector hessian|mser]\n"
      "        [--structure 2|3|4] [--vertex-descriptor none|sift]\n"
      "        [--encoding float32|int16|int8]\n"
      "        MODEL.png... -o OUT.kgi     compile model images into one index\n"
      "  detect --index I.kgi [--json] [--draw OUT.png] SCENE...\n"
      "                                    find the index's models in scene images\n"
      "  demo [--out DIR]                  build box.png from opencv-doc and find it\n"
      "                                    in box_in_scene.png\n"
      "  eval --dataset DIR [--subsets a,b] [--crops N] [--size S] [--centre]\n"
      "       [--seed N] [--set NAME=VALUE]... [--csv FILE]\n"
      "                                    crops of img1 found in img2..6 (Oxford layout)\n"
      "  inspect I.kgi                     header, parameters, sections (checksums\n"
      "                                    verified), models and bytes per arc\n"
      "  help                              this text\n");
}

int run(int argc, char** argv) {
  if (argc < 2) {
    usage(stderr);
    return 2;
  }
  const std::string command = argv[1];
  kg::cli::Args args(argv + 2, argv + argc);
  if (command == "build") return kg::cli::cmd_build(args);
  if (command == "detect") return kg::cli::cmd_detect(args);
  if (command == "demo") return kg::cli::cmd_demo(args);
  if (command == "eval") return kg::cli::cmd_eval(args);
  if (command == "inspect") return kg::cli::cmd_inspect(args);
  if (command == "help" || command == "--help" || command == "-h") {
    usage(stdout);
    return 0;
  }
  return kg::cli::fail("unknown command '" + command + "' (see keygraph help)");
}

}  // namespace

int main(int argc, char** argv) {
  // Last resort (e.g. std::bad_alloc, cv::Exception): one line and a
  // non-zero exit instead of std::terminate's multi-line abort.
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    return kg::cli::fail(std::string("internal error: ") + e.what());
  }
}
