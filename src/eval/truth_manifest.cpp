#include "eval/truth_manifest.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "eval/quad_geometry.h"

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
  if (out.empty() || std::any_of(out.begin(), out.end(), [](auto& s) { return s.empty(); })) {
    error = std::string("\"") + field + "\" must be a model name or a list of names";
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
  const double det = h[0] * (h[4] * h[8] - h[5] * h[7]) - h[1] * (h[3] * h[8] - h[5] * h[6]) +
                     h[2] * (h[3] * h[7] - h[4] * h[6]);
  if (h[8] == 0 || !std::isfinite(det) || det == 0) {
    error = "\"homography\" is singular or has h33 = 0";
    return false;
  }
  for (double& v : h) v /= h[8];
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
  const Json line = Json::parse(text.begin(), text.end(), nullptr, false);
  if (line.is_discarded()) {
    error = "not valid JSON";
    return false;
  }
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
      line["scene"].get<std::string>().empty()) {
    error = "\"scene\" must be an image path";
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

Status read_truth_manifest(const std::string& path, TruthManifest& out) {
  out.path = path;
  out.scenes.clear();
  std::ifstream in(path, std::ios::binary);
  if (!in) return {StatusCode::kNotFound, path + ": cannot open the manifest"};
  const std::filesystem::path base = std::filesystem::path(path).parent_path();
  std::string text;
  for (int number = 1; std::getline(in, text); ++number) {
    if (!text.empty() && text.back() == '\r') text.pop_back();
    const std::size_t first = text.find_first_not_of(" \t");
    if (first == std::string::npos || text[first] == '#') continue;
    TruthScene scene;
    std::string error;
    if (!parse_truth_line(text, scene, error))
      return {StatusCode::kCorruptData, path + ":" + std::to_string(number) + ": " + error};
    scene.line = number;
    const std::filesystem::path p(scene.scene);
    scene.path = p.is_absolute() ? p.string() : (base / p).string();
    out.scenes.push_back(std::move(scene));
  }
  if (in.bad()) return {StatusCode::kIoError, path + ": read error"};
  if (out.scenes.empty()) return {StatusCode::kCorruptData, path + ": no scenes in the manifest"};
  return Status::ok();
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
