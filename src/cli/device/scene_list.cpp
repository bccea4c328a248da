#include "cli/device/scene_list.h"

#include <filesystem>
#include <system_error>

#include "platform/files/file_source.h"

namespace kg::cli {

std::string expand_scene_paths(const std::vector<std::string>& args,
                               std::vector<std::string>& out) {
  out.clear();
  for (const std::string& arg : args) {
    std::error_code ec;
    if (!std::filesystem::is_directory(arg, ec)) {
      out.push_back(arg);
      continue;
    }
    std::vector<std::string> files;
    if (Status s = platform::list_image_files(arg, files); !s) return s.message();
    if (files.empty()) return arg + ": a directory with no image files";
    out.insert(out.end(), files.begin(), files.end());
  }
  return {};
}

}  // namespace kg::cli
