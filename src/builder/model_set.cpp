#include "builder/model_set.h"

#include <sys/resource.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>

#include <algorithm>
#include <filesystem>
#include <mutex>
#include <set>

#include "builder/model_views.h"
#include "builder/parallel.h"
#include "platform/files/regular_file.h"

namespace kg {

namespace {

namespace fs = std::filesystem;

// Bytes this process may still take: the address-space limit (ulimit -v)
// less what it has mapped, and at most the machine's memory.
std::uint64_t memory_left() {
  const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGESIZE);
  std::uint64_t left =
      pages > 0 && page > 0 ? static_cast<std::uint64_t>(pages) * page : std::uint64_t{1} << 34;
  struct rlimit limit {};
  if (::getrlimit(RLIMIT_AS, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY) {
    std::uint64_t mapped = 0;
    if (std::FILE* statm = std::fopen("/proc/self/statm", "r")) {
      unsigned long long size_pages = 0;
      if (std::fscanf(statm, "%llu", &size_pages) == 1 && page > 0)
        mapped = size_pages * static_cast<std::uint64_t>(page);
      std::fclose(statm);
    }
    const std::uint64_t cap = limit.rlim_cur;
    left = std::min(left, cap > mapped ? cap - mapped : 0);
  }
  return left;
}

std::string gigabytes(std::uint64_t bytes) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.1f GB", static_cast<double>(bytes) / 1e9);
  return text;
}

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
  std::string text;
  if (Status s = platform::read_text_file(path, text, kMaxModelsJsonBytes, "a models.json"); !s)
    return s;
  std::vector<ModelEntry> entries;
  std::string error;
  if (!parse_models_json(text, entries, error))
    return {StatusCode::kCorruptData, path + ": " + error};
  const fs::path base = fs::path(path).parent_path();
  for (ModelEntry& e : entries) {
    ModelSource s;
    s.name = std::move(e.name);
    const fs::path p(e.file);
    s.path = p.is_absolute() ? p.string() : (base / p).string();
    if (e.has_roi) s.roi = cv::Rect(e.roi[0], e.roi[1], e.roi[2], e.roi[3]);
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

Status load_model_images(const std::vector<ModelSource>& sources, const ViewParams* views,
                         ImageLoader load, std::vector<cv::Mat>& grays) {
  grays.clear();
  if (sources.size() > static_cast<std::size_t>(kMaxModels))
    return {StatusCode::kResourceExhausted, std::to_string(sources.size()) + " models, over the " +
                                                std::to_string(kMaxModels) +
                                                " one set may have; build them in smaller sets"};
  std::set<std::string> seen;
  for (const ModelSource& source : sources) {
    if (source.name.empty())
      return {StatusCode::kInvalidArgument, "empty model name for " + source.path};
    if (!seen.insert(source.name).second)
      return {StatusCode::kInvalidArgument, "duplicate model name '" + source.name + "'"};
  }
  // Then the images, on this thread (a loader may redirect the process's
  // stderr while it decodes): a set too large for memory fails before it
  // has taken it.
  const std::uint64_t room = memory_left() / 4 * 3;  // the rest: libraries, threads, slack
  long long pixels = 0;
  for (const ModelSource& source : sources) {
    cv::Mat gray;
    Status s = load_model_image(source, load, gray);
    if (s && views != nullptr) {
      if (s = check_view_canvas(gray.cols, gray.rows, *views); !s)
        s = {s.code(), source.path + ": " + s.message()};
    }
    pixels += static_cast<long long>(gray.cols) * gray.rows;
    const std::uint64_t need = static_cast<std::uint64_t>(pixels) * kBuildBytesPerModelPixel;
    if (s && need > room) {
      s = {StatusCode::kResourceExhausted,
           "the models would need about " + gigabytes(need) + " to build (" +
               std::to_string(kBuildBytesPerModelPixel) + " bytes per model pixel; reached at " +
               source.path + ", model " + std::to_string(grays.size() + 1) + " of " +
               std::to_string(sources.size()) + "), more than the " + gigabytes(room) +
               " this process may use: build them in smaller sets, or from smaller images"};
    }
    if (!s) {
      grays.clear();
      return s;
    }
    grays.push_back(gray);
  }
  return Status::ok();
}

Status build_model_set(const std::vector<ModelSource>& sources, const ModelBuildOptions& options,
                       ImageLoader load, std::vector<cv::Mat>& grays,
                       std::vector<BuiltModel>& models, const ProgressFn& progress) {
  models.clear();
  // Every name and image before any build: a bad input fails first.
  if (Status s = load_model_images(sources, &options.params.views, load, grays); !s) return s;
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
    if (fs::exists(fs::symlink_status(json, ec))) return read_models_json(json.string(), out);
    std::vector<fs::path> files;
    for (const fs::directory_entry& e : fs::directory_iterator(path, ec)) {
      if (e.is_regular_file(ec) && is_image_file(e.path())) files.push_back(e.path());
    }
    if (files.size() > static_cast<std::size_t>(kMaxModels))
      return {StatusCode::kResourceExhausted, path + ": " + std::to_string(files.size()) +
                                                  " model images, over the " +
                                                  std::to_string(kMaxModels) + " one set may have"};
    std::sort(files.begin(), files.end());
    for (const fs::path& f : files) out.push_back({f.stem().string(), f.string(), std::nullopt});
    if (out.empty()) return {StatusCode::kNotFound, path + ": no model images in the directory"};
    return Status::ok();
  }
  if (fs::exists(fs::symlink_status(path, ec))) return read_models_json(path, out);
  return {StatusCode::kNotFound, path + ": no such models directory or models.json"};
}

}  // namespace kg
