#include "builder/model_set.h"

#include <cstdint>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <set>
#include <sstream>

#include <nlohmann/json.hpp>

#include "builder/parallel.h"

namespace kg {

namespace {

namespace fs = std::filesystem;

std::string rect_text(const cv::Rect& r) {
  return std::to_string(r.x) + "," + std::to_string(r.y) + "," + std::to_string(r.width) + "," +
         std::to_string(r.height);
}

bool is_image_file(const fs::path& p) {
  std::string ext = p.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  for (const char* e :
       {".png", ".jpg", ".jpeg", ".pgm", ".ppm", ".bmp", ".tif", ".tiff", ".webp"}) {
    if (ext == e) return true;
  }
  return false;
}

Status read_models_json(const std::string& path, std::vector<ModelSource>& out) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return {StatusCode::kNotFound, path + ": cannot open"};
  std::stringstream text;
  text << in.rdbuf();
  const nlohmann::json doc = nlohmann::json::parse(text.str(), nullptr, false);
  const auto bad = [&](const std::string& what) {
    return Status{StatusCode::kCorruptData, path + ": " + what};
  };
  if (doc.is_discarded()) return bad("not valid JSON");
  if (!doc.is_object() || doc.empty())
    return bad("expected an object mapping model names to image files");
  const fs::path base = fs::path(path).parent_path();
  for (const auto& [name, value] : doc.items()) {
    ModelSource s;
    s.name = name;
    const nlohmann::json* file = &value;
    if (value.is_object()) {
      if (!value.contains("file")) return bad("model \"" + name + "\" has no \"file\"");
      file = &value["file"];
      if (value.contains("roi")) {
        const nlohmann::json& r = value["roi"];
        if (!r.is_array() || r.size() != 4 ||
            !std::all_of(r.begin(), r.end(), [](auto& v) { return v.is_number_integer(); }))
          return bad("model \"" + name + "\": \"roi\" must be [x, y, width, height] in pixels");
        const cv::Rect roi(r[0].get<int>(), r[1].get<int>(), r[2].get<int>(), r[3].get<int>());
        if (roi.x < 0 || roi.y < 0 || roi.width <= 0 || roi.height <= 0)
          return bad("model \"" + name + "\": bad \"roi\" " + rect_text(roi));
        s.roi = roi;
      }
    }
    if (!file->is_string() || file->get<std::string>().empty())
      return bad("model \"" + name + "\": expected an image file name");
    const fs::path p(file->get<std::string>());
    s.path = p.is_absolute() ? p.string() : (base / p).string();
    out.push_back(std::move(s));
  }
  return Status::ok();
}

}  // namespace

Status load_model_image(const ModelSource& source, ImageLoader load, cv::Mat& gray) {
  Status s = load(source.path, gray);
  if (!s || !source.roi) return s;
  const cv::Rect r = *source.roi;
  // In 64 bits: X + W can overflow an int.
  if (std::int64_t{r.x} + r.width > gray.cols || std::int64_t{r.y} + r.height > gray.rows)
    return {StatusCode::kInvalidArgument, "ROI " + rect_text(r) + " lies outside " + source.path +
                                              " (" + std::to_string(gray.cols) + "x" +
                                              std::to_string(gray.rows) + ")"};
  gray = gray(r).clone();
  return Status::ok();
}

Status build_model_set(const std::vector<ModelSource>& sources, const ModelBuildOptions& options,
                       ImageLoader load, std::vector<cv::Mat>& grays,
                       std::vector<BuiltModel>& models, const ProgressFn& progress) {
  grays.clear();
  models.clear();
  std::set<std::string> seen;
  // Names and images first, on this thread (a loader may redirect the
  // process's stderr while it decodes): a bad input fails before any build.
  for (const ModelSource& source : sources) {
    if (source.name.empty())
      return {StatusCode::kInvalidArgument, "empty model name for " + source.path};
    if (!seen.insert(source.name).second)
      return {StatusCode::kInvalidArgument, "duplicate model name '" + source.name + "'"};
    cv::Mat gray;
    if (Status s = load_model_image(source, load, gray); !s) {
      grays.clear();
      return s;
    }
    grays.push_back(gray);
  }
  // Each model is built alone from its own image, so the threads only
  // share the progress line; the models come out in source order.
  std::vector<BuiltModel> built(sources.size());
  std::mutex progress_mutex;
  int done = 0;
  Status s;
  try {
    s = parallel_for_status(sources.size(), options.threads, [&](std::size_t i) {
      Status b = build_model(grays[i], sources[i].name, options.params, built[i]);
      if (b && progress) {
        const std::lock_guard<std::mutex> lock(progress_mutex);
        progress(++done, static_cast<int>(sources.size()), sources[i].name);
      }
      return b;
    });
  } catch (...) {
    grays.clear();
    throw;
  }
  if (!s) {
    grays.clear();
    return s;
  }
  models = std::move(built);
  return Status::ok();
}

Status read_model_sources(const std::string& path, std::vector<ModelSource>& out) {
  out.clear();
  std::error_code ec;
  if (fs::is_directory(path, ec)) {
    const fs::path json = fs::path(path) / "models.json";
    if (fs::exists(json, ec)) return read_models_json(json.string(), out);
    std::vector<fs::path> files;
    for (const fs::directory_entry& e : fs::directory_iterator(path, ec)) {
      if (e.is_regular_file(ec) && is_image_file(e.path())) files.push_back(e.path());
    }
    std::sort(files.begin(), files.end());
    for (const fs::path& f : files) out.push_back({f.stem().string(), f.string(), std::nullopt});
    if (out.empty()) return {StatusCode::kNotFound, path + ": no model images in the directory"};
    return Status::ok();
  }
  if (fs::is_regular_file(path, ec)) return read_models_json(path, out);
  return {StatusCode::kNotFound, path + ": no such models directory or models.json"};
}

}  // namespace kg
