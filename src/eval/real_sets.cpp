#include "eval/real_sets.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <sstream>
#include <vector>

#include <nlohmann/json.hpp>

#include "eval/set_files.h"
namespace kg {

namespace {

namespace fs = std::filesystem;
using Json = nlohmann::ordered_json;

// `file` as the manifest at `manifest_path` refers to it.
std::string relative_to(const fs::path& file, const std::string& manifest_path) {
  std::error_code ec;
  const fs::path base = fs::weakly_canonical(fs::absolute(manifest_path).parent_path(), ec);
  const fs::path target = fs::weakly_canonical(fs::absolute(file), ec);
  const fs::path rel = target.lexically_relative(base);
  return rel.empty() ? target.string() : rel.string();
}

Status missing(const fs::path& p) {
  return {StatusCode::kNotFound, p.string() + ": not found (is this the set's directory?)"};
}

bool is_image(const fs::path& p) {
  const std::string e = p.extension().string();
  return e == ".jpg" || e == ".jpeg" || e == ".png" || e == ".JPG" || e == ".PNG";
}

// The model source frames of exit-signs/ (its README): the rectified crops
// model-exit-left.png and model-exit-right.png come from these two frames,
// whose names are their time stamps in seconds.
constexpr double kExitModelFrames[] = {263548.696465416, 264818.131419791};
constexpr double kExitExclusionSeconds = 30;
constexpr double kBurstGapSeconds = 5;

}  // namespace

Status convert_exit_signs(const std::string& dir, const std::string& manifest_path,
                          const std::string& split, ConvertedSet& out) {
  if (!split.empty() && split != "dev" && split != "test" && split != "model-bursts")
    return {StatusCode::kInvalidArgument,
            "--split takes dev, test or model-bursts, got '" + split + "'"};
  const fs::path root(dir), corners = root / "corners.txt", images = root / "images";
  std::error_code ec;
  for (const fs::path& p :
       {corners, images, root / "model-exit-left.png", root / "model-exit-right.png"}) {
    if (!fs::exists(fs::symlink_status(p, ec))) return missing(p);
  }
  if (!fs::is_directory(images, ec))
    return {StatusCode::kInvalidArgument, images.string() + ": not a directory"};
  std::vector<MarkedSign> marked;
  if (Status s = read_corners_file(corners.string(), marked); !s) return s;
  out.inputs = {corners.string(), (root / "model-exit-left.png").string(),
                (root / "model-exit-right.png").string()};
  std::map<std::string, Json> signs;  // image (relative to dir) -> instances
  for (const MarkedSign& m : marked) {
    Json instance = Json::object();
    instance["model"] = Json::array({"exit-left", "exit-right"});
    Json points = Json::array();
    for (int c = 0; c < 4; ++c)
      points.push_back(Json::array({m.corners[2 * c], m.corners[2 * c + 1]}));
    instance["corners"] = points;
    signs[m.image].push_back(instance);
  }
  struct Frame {
    double time;
    std::string image;  // relative to dir
  };
  std::vector<Frame> frames;
  int excluded = 0;
  for (const fs::directory_entry& e : fs::directory_iterator(images, ec)) {
    if (!e.is_regular_file(ec) || !is_image(e.path())) continue;
    out.inputs.push_back(e.path().string());
    double time = 0;
    try {
      time = std::stod(e.path().stem().string());
    } catch (const std::exception&) {
      return {StatusCode::kCorruptData,
              e.path().string() + ": expected a time stamp in seconds as the file name"};
    }
    bool near_model = false;
    for (const double m : kExitModelFrames)
      near_model = near_model || std::abs(time - m) <= kExitExclusionSeconds;
    if (near_model) ++excluded;
    if (near_model == (split == "model-bursts"))
      frames.push_back({time, "images/" + e.path().filename().string()});
  }
  std::sort(frames.begin(), frames.end(),
            [](const Frame& a, const Frame& b) { return a.time < b.time; });
  // Bursts: runs of frames each closer than kBurstGapSeconds to the previous.
  int burst = -1;
  double previous = -1e300;
  int kept_frames[2] = {0, 0}, kept_signs[2] = {0, 0}, bursts[2] = {0, 0};
  std::ostringstream manifest;
  for (const Frame& f : frames) {
    if (f.time - previous >= kBurstGapSeconds) ++bursts[(++burst) % 2];
    previous = f.time;
    const int half = burst % 2;  // 0: dev, 1: test
    const auto it = signs.find(f.image);
    const int count = it == signs.end() ? 0 : static_cast<int>(it->second.size());
    ++kept_frames[half];
    kept_signs[half] += count;
    if ((split == "dev" && half != 0) || (split == "test" && half != 1)) continue;  // else all
    Json line = Json::object();
    line["scene"] = relative_to(root / f.image, manifest_path);
    line["instances"] = it == signs.end() ? Json::array() : it->second;
    manifest << line.dump() << '\n';
  }
  if (ec) return {StatusCode::kIoError, images.string() + ": cannot list: " + ec.message()};
  out.manifest = manifest.str();
  Json models = Json::object();
  models["exit-left"] = relative_to(root / "model-exit-left.png", manifest_path);
  models["exit-right"] = relative_to(root / "model-exit-right.png", manifest_path);
  out.models_json = models.dump(2) + "\n";
  std::ostringstream summary;
  if (split == "model-bursts") {
    summary << "exit-signs: the " << frames.size() << " frames (" << kept_signs[0] + kept_signs[1]
            << " signs) within " << kExitExclusionSeconds
            << " s of a model's source frame, for a sanity check only (never a score)";
    out.summary = summary.str();
    return Status::ok();
  }
  summary << "exit-signs: " << frames.size() << " frames (" << kept_signs[0] + kept_signs[1]
          << " signs) kept, " << excluded << " within " << kExitExclusionSeconds
          << " s of a model's source frame left out; " << burst + 1 << " bursts: dev "
          << kept_frames[0] << " frames (" << kept_signs[0] << " signs, " << bursts[0]
          << " bursts), test " << kept_frames[1] << " frames (" << kept_signs[1] << " signs, "
          << bursts[1] << " bursts)";
  if (!split.empty()) summary << "; this manifest: " << split;
  out.summary = summary.str();
  return Status::ok();
}

Status convert_planar_pairs(const std::string& dir, const std::string& manifest_path,
                            ConvertedSet& out) {
  const fs::path root(dir);
  std::error_code ec;
  if (!fs::is_directory(root, ec)) return missing(root);
  std::vector<std::string> names;
  for (const fs::directory_entry& e : fs::directory_iterator(root, ec)) {
    const std::string f = e.path().filename().string();
    const std::string suffix = "_H_A_to_B.txt";
    if (f.size() > suffix.size() && f.compare(f.size() - suffix.size(), suffix.size(), suffix) == 0)
      names.push_back(f.substr(0, f.size() - suffix.size()));
  }
  if (names.empty()) return {StatusCode::kNotFound, dir + ": no <name>_H_A_to_B.txt files"};
  std::sort(names.begin(), names.end());
  auto image_of = [&](const std::string& stem) -> fs::path {
    for (const char* ext : {".png", ".jpg", ".jpeg", ".JPG", ".PNG"}) {
      const fs::path p = root / (stem + ext);
      if (fs::exists(p, ec)) return p;
    }
    return {};
  };
  std::ostringstream manifest;
  Json models = Json::object();
  for (const std::string& name : names) {
    const fs::path a = image_of(name + "A"), b = image_of(name + "B");
    if (a.empty()) return missing(root / (name + "A.*"));
    if (b.empty()) return missing(root / (name + "B.*"));
    const fs::path h_path = root / (name + "_H_A_to_B.txt");
    Homography h{};
    if (Status s = read_homography_file(h_path.string(), h); !s) return s;
    out.inputs.insert(out.inputs.end(), {h_path.string(), a.string(), b.string()});
    models[name] = relative_to(a, manifest_path);
    Json instance = Json::object();
    instance["model"] = name;
    instance["homography"] = h;
    Json line = Json::object();
    line["scene"] = relative_to(b, manifest_path);
    line["search"] = Json::array({name});
    line["instances"] = Json::array({instance});
    manifest << line.dump() << '\n';
  }
  out.manifest = manifest.str();
  out.models_json = models.dump(2) + "\n";
  out.summary = "planar-pairs: " + std::to_string(names.size()) +
                " pairs, each scene B searched with its own model A only";
  return Status::ok();
}

Status convert_negatives(const std::string& dir, const std::string& manifest_path,
                         ConvertedSet& out) {
  const fs::path root(dir);
  std::error_code ec;
  if (!fs::is_directory(root, ec)) return missing(root);
  std::vector<fs::path> files;
  for (const fs::directory_entry& e : fs::directory_iterator(root, ec)) {
    if (e.is_regular_file(ec) && is_image(e.path())) files.push_back(e.path());
  }
  for (const fs::path& f : files) out.inputs.push_back(f.string());
  if (files.empty()) return {StatusCode::kNotFound, dir + ": no images"};
  std::sort(files.begin(), files.end());
  std::ostringstream manifest;
  for (const fs::path& f : files) {
    Json line = Json::object();
    line["scene"] = relative_to(f, manifest_path);
    line["instances"] = Json::array();
    manifest << line.dump() << '\n';
  }
  out.manifest = manifest.str();
  out.summary = "negatives: " + std::to_string(files.size()) + " photos without instances";
  return Status::ok();
}

}  // namespace kg
