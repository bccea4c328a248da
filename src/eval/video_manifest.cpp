#include "eval/video_manifest.h"

#include <utility>

#include <nlohmann/json.hpp>

#include "builder/strict_json.h"
#include "platform/files/regular_file.h"

namespace kg {

Status parse_video_manifest(std::string_view text, const std::string& path, VideoManifest& out) {
  out = VideoManifest{};
  // Each line as the truth manifest has it, a frame without ground truth
  // given an empty list of instances and remembered by its line.
  std::string rewritten;
  rewritten.reserve(text.size() + 64);
  std::vector<int> unannotated;                    // line numbers
  std::vector<std::pair<int, std::string>> parts;  // line number, name
  std::size_t begin = 0;
  for (int number = 1; begin < text.size(); ++number) {
    std::size_t end = text.find('\n', begin);
    if (end == std::string_view::npos) end = text.size();
    std::string_view line = text.substr(begin, end - begin);
    begin = end + 1;
    const std::size_t first = line.find_first_not_of(" \t\r");
    constexpr std::string_view kPart = "# part:";
    if (first != std::string_view::npos && line.substr(first, kPart.size()) == kPart) {
      std::string_view name = line.substr(first + kPart.size());
      while (!name.empty() && (name.front() == ' ' || name.front() == '\t')) name.remove_prefix(1);
      while (!name.empty() && (name.back() == ' ' || name.back() == '\r')) name.remove_suffix(1);
      parts.emplace_back(number, std::string(name));
    }
    if (first != std::string_view::npos && line[first] != '#' &&
        line.size() <= kMaxManifestLineBytes) {
      nlohmann::json json;
      std::string error;
      if (parse_json_strict(line, json, error) && json.is_object() && !json.contains("instances") &&
          json.contains("scene")) {
        if (json.size() != 1)
          return {StatusCode::kCorruptData,
                  path + ":" + std::to_string(number) +
                      ": a frame without ground truth has \"scene\" alone"};
        json["instances"] = nlohmann::json::array();
        rewritten += json.dump();
        rewritten += '\n';
        unannotated.push_back(number);
        continue;
      }
    }
    rewritten.append(line);
    rewritten += '\n';
  }
  if (Status s = parse_truth_manifest(rewritten, path, out.truth); !s) return s;
  std::size_t u = 0, p = 0;
  std::string part;
  for (const TruthScene& scene : out.truth.scenes) {
    while (u < unannotated.size() && unannotated[u] < scene.line) ++u;
    out.annotated.push_back(!(u < unannotated.size() && unannotated[u] == scene.line));
    while (p < parts.size() && parts[p].first < scene.line) part = parts[p++].second;
    out.part.push_back(part);
  }
  return Status::ok();
}

Status read_video_manifest(const std::string& path, VideoManifest& out) {
  out = VideoManifest{};
  std::string text;
  if (Status s = platform::read_text_file(path, text, kMaxManifestBytes, "a manifest"); !s)
    return s;
  return parse_video_manifest(text, path, out);
}

}  // namespace kg
