// Image files for the desktop commands, through OpenCV (builder/image_io.h).
#include <filesystem>
#include <string>

#include <opencv2/imgcodecs.hpp>

#include "builder/image_io.h"
#include "cli/commands.h"
#include "platform/files/held_stderr.h"
#include "platform/files/output_file.h"

namespace kg::cli {

Status load_image(const std::string& path, cv::Mat& gray) {
  // Decoders' complaints are held: on failure our one line replaces them,
  // on success they are passed on (e.g. libpng's sRGB profile warnings).
  platform::StderrHold decoder_messages;
  decoder_messages.hold();
  Status s = load_gray(path, gray);
  decoder_messages.release(s.is_ok());
  return s;
}

bool write_image_atomically(const std::string& path, const cv::Mat& image,
                            const std::vector<std::string>& inputs, std::string& error) {
  std::string ext = std::filesystem::path(path).extension().string();
  if (ext.empty()) {
    error = path + ": output image needs an extension such as .png";
    return false;
  }
  // The temporary keeps the extension: the encoder is chosen from it.
  platform::OutputFile out;
  Status s = out.create(path, inputs, ext);
  if (s) s = out.close();
  if (s) {
    // The encoder's own complaint (on several lines) is held: our one line
    // replaces it.
    platform::StderrHold encoder_messages;
    encoder_messages.hold();
    bool written = false;
    try {
      written = cv::imwrite(out.temp_path(), image);
    } catch (const cv::Exception&) {
      written = false;
    }
    encoder_messages.release(written);
    if (!written)
      s = {StatusCode::kIoError,
           "cannot write image " + path + " (OpenCV cannot write this picture as " + ext + ")"};
  }
  if (s) s = out.commit();
  if (!s) error = s.message();
  return s.is_ok();
}

}  // namespace kg::cli
