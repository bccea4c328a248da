#include "cli/device/draw_targets.h"

#include <filesystem>
#include <map>
#include <system_error>

#include "cli/device/command_line.h"
#include "platform/files/output_file.h"

namespace kg::cli {

std::string plan_drawings(const std::string& draw, const std::vector<std::string>& scenes,
                          const std::string& dir_ext,
                          const std::function<bool(const std::string&)>& writable,
                          const std::vector<std::string>& inputs, std::vector<std::string>& out) {
  namespace fs = std::filesystem;
  out.clear();
  std::error_code ec;
  const bool into_directory = fs::is_directory(draw, ec) || (!draw.empty() && draw.back() == '/');
  if (into_directory) {
    if (!fs::is_directory(draw, ec)) return "--draw " + draw + ": no such directory";
    std::map<std::string, const std::string*> drawn_from;
    for (const std::string& scene : scenes) {
      const std::string path =
          (fs::path(draw) / (fs::path(scene).stem().string() + dir_ext)).string();
      const auto [it, inserted] = drawn_from.emplace(path, &scene);
      if (!inserted && *it->second != scene) {
        return "--draw: " + *it->second + " and " + scene + " would both be drawn to " + path +
               "; give the scenes distinct names";
      }
      out.push_back(path);
    }
  } else {
    if (fs::path(draw).extension().empty()) {
      return "--draw " + draw + ": not a directory, and no picture extension (such as " + dir_ext +
             ") to make it a file name";
    }
    if (!writable(draw))
      return "--draw " + draw + ": this keygraph cannot write that picture format";
    if (std::string error = draw_paths(draw, scenes, out); !error.empty()) return error;
  }
  // Each picture could be written: its temporary is made and removed.
  for (const std::string& path : out) {
    platform::OutputFile probe;
    if (Status s = probe.create(path, inputs, fs::path(path).extension().string()); !s)
      return "--draw " + s.message();
    probe.discard();
  }
  return {};
}

}  // namespace kg::cli
