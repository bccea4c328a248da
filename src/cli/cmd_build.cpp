// keygraph build [--name NAME]... [--detector hessian|mser] [--structure 2|3|4]
//                [--vertex-descriptor none|sift] [--encoding float32|int16|int8]
//                [--min-size PX] [--max-tilt DEG] [--roi X,Y,W,H]
//                [--set NAME=VALUE]... [--draw-model DIR] [--no-look-alikes]
//                MODEL... -o OUT.kgi
// --min-size and --max-tilt set the simulated views (views.min_size,
// views.max_tilt; --max-tilt also asks for two tilt levels when none is set).
// --name and --roi apply to the model image that follows them: --roi makes
// the model that rectangle of the image (model pixel (0,0) is image pixel
// (X,Y)); without --name the model is named after the file's stem.
// Every build measures the model quality report (build/model_quality.h),
// stores it in the index and prints it; --no-look-alikes skips rendering
// each model as a scene. --draw-model DIR writes DIR/NAME.png per model:
// its keypoints and strongest keygraphs.
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <sstream>
#include <system_error>

#include <opencv2/imgcodecs.hpp>

#include "build/image_io.h"
#include "build/model_builder.h"
#include "build/model_quality.h"
#include "build/model_set.h"
#include "build/param_overrides.h"
#include "cli/commands.h"
#include "cli/device/quality_report.h"
#include "core/param_names.h"
#include "platform/files/output_file.h"

namespace kg::cli {

namespace {

bool parse_roi(const std::string& text, cv::Rect& roi) {
  std::istringstream in(text);
  char c1 = 0, c2 = 0, c3 = 0;
  in >> roi.x >> c1 >> roi.y >> c2 >> roi.width >> c3 >> roi.height;
  return in && in.peek() == EOF && c1 == ',' && c2 == ',' && c3 == ',' && roi.x >= 0 &&
         roi.y >= 0 && roi.width > 0 && roi.height > 0;
}

// A file name for a model name: characters other than letters, digits,
// '-', '_' and '.' become '_' (a name may hold '/'), never hidden.
std::string picture_name(const std::string& model) {
  std::string name;
  for (char c : model) {
    const bool safe = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                      c == '-' || c == '_' || c == '.';
    name += safe ? c : '_';
  }
  if (name.empty() || name[0] == '.') name.insert(name.begin(), '_');
  return name + ".png";
}

// One PNG per model into `dir` (created if missing), each written to a
// temporary name and renamed: no half-written picture is left behind.
Status draw_models(const std::string& dir, const std::vector<BuiltModel>& models,
                   const std::vector<cv::Mat>& grays) {
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (!fs::is_directory(dir, ec))
    return {StatusCode::kIoError, "--draw-model " + dir + ": not a directory"};
  for (std::size_t m = 0; m < models.size(); ++m) {
    const fs::path target = fs::path(dir) / picture_name(models[m].name);
    const fs::path temporary = fs::path(dir) / (".kg-tmp-" + picture_name(models[m].name));
    bool written = false;
    try {
      written = cv::imwrite(temporary.string(), draw_model(grays[m], models[m]));
    } catch (const cv::Exception&) {
      written = false;
    }
    if (!written) {
      fs::remove(temporary, ec);
      return {StatusCode::kIoError, "--draw-model: cannot write " + target.string()};
    }
    fs::rename(temporary, target, ec);
    if (ec) {
      fs::remove(temporary, ec);
      return {StatusCode::kIoError, "--draw-model: cannot write " + target.string()};
    }
  }
  return Status::ok();
}

}  // namespace

int cmd_build(const Args& args) {
  std::vector<std::string> names, paths;
  std::vector<std::optional<cv::Rect>> rois;
  std::optional<cv::Rect> pending_roi;
  std::optional<std::string> pending_name;
  std::string output, draw_dir;
  bool look_alikes = true;
  Params params;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    const bool has_value = i + 1 < args.size();
    if (a == "--name" || a == "-o" || a == "--output" || a == "--detector" || a == "--structure" ||
        a == "--vertex-descriptor" || a == "--encoding" || a == "--roi" || a == "--set" ||
        a == "--min-size" || a == "--max-tilt" || a == "--draw-model") {
      if (!has_value) return fail("build: " + a + " needs a value");
      const std::string& v = args[++i];
      if (a == "--draw-model") {
        draw_dir = v;
      } else if (a == "--name") {
        if (pending_name) return fail("build: two --name options for one model image");
        pending_name = v;
      } else if (a == "--roi") {
        cv::Rect roi;
        if (!parse_roi(v, roi)) return fail("build: --roi takes X,Y,W,H (pixels), got '" + v + "'");
        pending_roi = roi;
      } else if (a == "--detector") {
        if (v == "hessian") {
          params.keypoints.detector = KeypointDetector::kHessian;
        } else if (v == "mser") {
          params.keypoints.detector = KeypointDetector::kMser;
        } else {
          return fail("build: unknown detector '" + v + "' (hessian or mser)");
        }
      } else if (a == "--vertex-descriptor") {
        if (v == "sift") {
          params.descriptor.vertex_descriptor = VertexDescriptor::kSift;
        } else if (v == "none") {
          params.descriptor.vertex_descriptor = VertexDescriptor::kNone;
        } else {
          return fail("build: unknown vertex descriptor '" + v + "' (none or sift)");
        }
      } else if (a == "--encoding") {
        if (!parse_enum(v.c_str(), params.descriptor.encoding))
          return fail("build: unknown encoding '" + v + "' (float32, int16 or int8)");
      } else if (a == "--set") {
        if (Status s = apply_param_override(v, params); !s) return fail("build: " + s.message());
      } else if (a == "--min-size" || a == "--max-tilt") {
        const std::string name = a == "--min-size" ? "views.min_size" : "views.max_tilt";
        if (Status s = apply_param_override(name + "=" + v, params); !s)
          return fail("build: " + a + ": " + s.message());
        if (a == "--max-tilt" && params.views.tilt_levels == 0) params.views.tilt_levels = 2;
      } else if (a == "--structure") {
        if (v != "2" && v != "3" && v != "4") return fail("build: --structure takes 2, 3 or 4");
        params.graph.structure = static_cast<Structure>(v[0] - '0');
      } else {
        output = v;
      }
    } else if (a == "--no-look-alikes") {
      look_alikes = false;
    } else if (!a.empty() && a[0] == '-') {
      return fail("build: unknown option " + a);
    } else {
      paths.push_back(a);
      rois.push_back(pending_roi);
      pending_roi.reset();
      names.push_back(pending_name ? *pending_name : std::filesystem::path(a).stem().string());
      pending_name.reset();
    }
  }
  if (pending_roi) return fail("build: --roi must come before the model image it applies to");
  if (pending_name) return fail("build: --name must come before the model image it applies to");
  if (paths.empty()) return fail("build: no model images given");
  if (output.empty()) return fail("build: no output given (-o OUT.kgi)");

  // The output first: a device node, a directory or one of the model
  // images as -o fails before the build, and an interrupted build leaves
  // nothing behind (the temporary is removed on SIGINT and SIGTERM).
  platform::OutputFile out;
  if (Status s = out.create(output, paths); !s) return fail("build: -o " + s.message());

  std::vector<ModelSource> sources;
  for (std::size_t i = 0; i < paths.size(); ++i) sources.push_back({names[i], paths[i], rois[i]});
  ModelBuildOptions options;
  options.params = params;
  std::vector<cv::Mat> grays;
  std::vector<BuiltModel> models;
  if (Status s = build_model_set(sources, options, load_image, grays, models); !s)
    return fail("build: " + s.message());
  for (const BuiltModel& model : models) {
    // Its size alone: what this model adds to an index.
    std::vector<std::uint8_t> bytes;
    if (Status s = serialize_index({model}, options.params, bytes); !s)
      return fail("build: " + s.message());
    std::printf("%s: %zu views, %zu keypoints, %zu arcs, %llu keygraphs, %.1f KB alone\n",
                model.name.c_str(), model.views.size(), model.keypoints.size(), model.arcs.size(),
                static_cast<unsigned long long>(model.keygraphs),
                static_cast<double>(bytes.size()) / 1024.0);
  }
  QualityOptions quality_options;
  quality_options.look_alikes = look_alikes;
  QualityReport quality;
  if (Status s = measure_quality(models, grays, options.params, quality_options, quality); !s)
    return fail("build: " + s.message());
  // The report as inspect prints it: from the index's own bytes.
  std::vector<std::uint8_t> bytes;
  if (Status s = serialize_index(models, options.params, bytes, &quality); !s)
    return fail("build: " + s.message());
  const std::unique_ptr<std::uint8_t[]> storage(new std::uint8_t[bytes.size() + 64]);
  std::uint8_t* aligned =
      storage.get() + (64 - reinterpret_cast<std::uintptr_t>(storage.get()) % 64) % 64;
  std::copy(bytes.begin(), bytes.end(), aligned);
  ModelIndex index;
  if (Status s = ModelIndex::view(aligned, bytes.size(), index); !s)
    return fail("build: " + s.message());
  print_quality_report(index, false, stdout);
  if (!draw_dir.empty()) {
    if (Status s = draw_models(draw_dir, models, grays); !s) return fail("build: " + s.message());
  }
  Status s = out.write(bytes.data(), bytes.size());
  if (s) s = out.commit();
  if (!s) return fail(s.message());
  std::printf("wrote %s (%zu models)\n", output.c_str(), models.size());
  return 0;
}

}  // namespace kg::cli
