#include "eval/truth_manifest.h"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include <nlohmann/json.hpp>

#include "builder/strict_json.h"
#include "eval/quad_geometry.h"
#include "platform/files/regular_file.h"

namespace kg {

namespace {

using Json = nlohmann::json;

bool read_names(const Json& value, const char* field, std::vector<std::string>& out,
                std::string& error) {
  out.clear();
  if (value.is_string()) {
    out.push_back(value.get<std::string>());
  } else if (value.is_array() && !value.empty()) {
    for (const Json& v : value) {
      if (!v.is_string()) break;
      out.push_back(v.get<std::string>());
    }
    if (out.size() != value.size()) out.clear();
  }
  if (out.empty() || std::any_of(out.begin(), out.end(),
                                 [](auto& s) { return s.empty() || has_control_character(s); })) {
    error = std::string("\"") + field +
            "\" must be a model name or a list of names (without control characters)";
    return false;
  }
  return true;
}

bool read_number(const Json& v, double& out) {
  if (!v.is_number()) return false;
  out = v.get<double>();
  return std::isfinite(out);
}

bool read_corners(const Json& value, Point2f (&corners)[4], std::string& error) {
  error = "\"corners\" must be four [x, y] points";
  if (!value.is_array() || value.size() != 4) return false;
  for (std::size_t i = 0; i < 4; ++i) {
    const Json& p = value[i];
    double x = 0, y = 0;
    if (!p.is_array() || p.size() != 2 || !read_number(p[0], x) || !read_number(p[1], y))
      return false;
    if (std::abs(x) > 1e7 || std::abs(y) > 1e7) return false;
    corners[i] = {static_cast<float>(x), static_cast<float>(y)};
  }
  if (!is_simple_quad(corners)) {
    error = "\"corners\" cross or have no area: give them around the outline";
    return false;
  }
  return true;
}

bool read_homography(const Json& value, Homography& h, std::string& error) {
  error = "\"homography\" must be 9 numbers (row-major, model pixels -> scene pixels)";
  if (!value.is_array() || value.size() != 9) return false;
  for (std::size_t i = 0; i < 9; ++i) {
    if (!read_number(value[i], h[i])) return false;
  }
  if (!normalise_homography(h)) {
    error =
        "\"homography\" is singular, has h33 = 0, or does not normalise to h33 = 1 in finite "
        "numbers";
    return false;
  }
  return true;
}

bool read_instance(const Json& value, TruthInstance& out, std::string& error) {
  if (!value.is_object()) {
    error = "each instance must be an object";
    return false;
  }
  for (const auto& [key, v] : value.items()) {
    (void)v;
    if (key != "model" && key != "corners" && key != "homography") {
      error = "unknown instance field \"" + key + "\"";
      return false;
    }
  }
  if (!value.contains("model")) {
    error = "an instance has no \"model\"";
    return false;
  }
  if (!read_names(value["model"], "model", out.models, error)) return false;
  const bool corners = value.contains("corners"), homography = value.contains("homography");
  if (corners == homography) {
    error = "an instance needs either \"corners\" or \"homography\"";
    return false;
  }
  if (corners) return read_corners(value["corners"], out.corners, error);
  out.has_homography = true;
  if (out.models.size() != 1) {
    error = "a \"homography\" instance takes one model name (its outline is that model's)";
    return false;
  }
  return read_homography(value["homography"], out.homography, error);
}

}  // namespace

bool parse_truth_line(std::string_view text, TruthScene& out, std::string& error) {
  out.scene.clear();
  out.instances.clear();
  out.search.clear();
  if (text.size() > kMaxManifestLineBytes) {
    error = "line of " + std::to_string(text.size()) + " bytes, over the " +
            platform::byte_size_text(kMaxManifestLineBytes) + " a manifest line may have";
    return false;
  }
  Json line;
  if (!parse_json_strict(text, line, error)) return false;
  if (!line.is_object()) {
    error = "a line must be a JSON object with \"scene\" and \"instances\"";
    return false;
  }
  for (const auto& [key, v] : line.items()) {
    (void)v;
    if (key != "scene" && key != "instances" && key != "search") {
      error = "unknown field \"" + key + "\"";
      return false;
    }
  }
  if (!line.contains("scene") || !line["scene"].is_string() ||
      line["scene"].get<std::string>().empty() ||
      has_control_character(line["scene"].get<std::string>())) {
    error = "\"scene\" must be an image path (without control characters)";
    return false;
  }
  out.scene = line["scene"].get<std::string>();
  if (!line.contains("instances") || !line["instances"].is_array()) {
    error = "\"instances\" must be a list (empty for a scene without any of the models)";
    return false;
  }
  for (const Json& i : line["instances"]) {
    TruthInstance instance;
    if (!read_instance(i, instance, error)) return false;
    out.instances.push_back(std::move(instance));
  }
  if (line.contains("search") && !read_names(line["search"], "search", out.search, error))
    return false;
  return true;
}

Status parse_truth_manifest(std::string_view text, const std::string& path, TruthManifest& out) {
  out.path = path;
  out.scenes.clear();
  const std::filesystem::path base = std::filesystem::path(path).parent_path();
  std::size_t begin = 0;
  for (int number = 1; begin < text.size(); ++number) {
    std::size_t end = text.find('\n', begin);
    if (end == std::string_view::npos) end = text.size();
    std::string_view line = text.substr(begin, end - begin);
    begin = end + 1;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    const std::size_t first = line.find_first_not_of(" \t");
    if (first == std::string_view::npos || line[first] == '#') continue;
    TruthScene scene;
    std::string error;
    if (!parse_truth_line(line, scene, error))
      return {StatusCode::kCorruptData, path + ":" + std::to_string(number) + ": " + error};
    scene.line = number;
    const std::filesystem::path p(scene.scene);
    scene.path = p.is_absolute() ? p.string() : (base / p).string();
    out.scenes.push_back(std::move(scene));
  }
  if (out.scenes.empty()) return {StatusCode::kCorruptData, path + ": no scenes in the manifest"};
  return Status::ok();
}

Status read_truth_manifest(const std::string& path, TruthManifest& out) {
  out.path = path;
  out.scenes.clear();
  std::string text;
  if (Status s = platform::read_text_file(path, text, kMaxManifestBytes, "a manifest"); !s)
    return s;
  return parse_truth_manifest(text, path, out);
}

bool check_truth_models(const TruthScene& scene, const std::vector<std::string>& known,
                        std::string& error) {
  auto unknown = [&](const std::string& name) {
    if (std::find(known.begin(), known.end(), name) != known.end()) return false;
    error = "unknown model \"" + name + "\"";
    return true;
  };
  for (const TruthInstance& i : scene.instances) {
    for (const std::string& m : i.models) {
      if (unknown(m)) return false;
    }
  }
  for (const std::string& m : scene.search) {
    if (unknown(m)) return false;
  }
  return true;
}

}  // namespace kg
