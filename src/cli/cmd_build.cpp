// keygraph build: its options are the Options table below (keygraph build --help).
// --min-size, --max-scale and --max-tilt set the simulated views
// (views.min_size, views.max_scale, views.max_tilt; --max-tilt also sets the
// tilt levels, steps of about 0.5 in t as ASIFT's, unless views.tilt_levels
// is --set).
// --preset NAME starts from a named parameter set (keygraph/param_text.h)
// instead of the defaults, wherever it is on the command line: every other
// option applies over it.
// --name and --roi apply to the model image that follows them: --roi makes
// the model that rectangle of the image (model pixel (0,0) is image pixel
// (X,Y)); without --name the model is named after the file's stem.
// A MODEL argument may also be a directory (every image in it a model, or
// its models.json) or a models.json (names, files, ROIs; docs/EVAL.md), as
// eval --models reads them. --max-side PX downsamples each model image
// (after its ROI) to PX on its long edge, and decodes JPEG photos over the
// pixel limit at a reduced size first (load_model_photo()).
// Every build measures the model quality report (builder/model_quality.h),
// stores it in the index and prints it; --no-look-alikes skips rendering
// each model as a scene. --draw-model DIR writes DIR/NAME.png per model:
// its keypoints and strongest keygraphs.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <system_error>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "builder/image_io.h"
#include "builder/in_memory_index.h"
#include "builder/index_writer.h"
#include "builder/model_builder.h"
#include "builder/model_quality.h"
#include "builder/model_set.h"
#include "builder/model_views.h"
#include "builder/parallel.h"
#include "builder/progress.h"
#include "cli/commands.h"
#include "cli/device/options.h"
#include "cli/device/quality_report.h"
#include "core/index/index_format.h"
#include "core/params/param_names.h"
#include "keygraph/param_text.h"
#include "platform/files/output_file.h"
#include "platform/files/output_set.h"

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

// One PNG per model into `dir` (created if missing), all or nothing
// (platform::OutputSet: never over an input, no fixed temporary names).
Status draw_models(const std::string& dir, const std::vector<BuiltModel>& models,
                   const std::vector<cv::Mat>& grays, const std::vector<std::string>& inputs) {
  platform::OutputSet out(dir, inputs);
  for (std::size_t m = 0; m < models.size(); ++m) {
    const std::string target = (std::filesystem::path(dir) / picture_name(models[m].name)).string();
    std::vector<std::uint8_t> png;
    bool encoded = false;
    try {
      encoded = cv::imencode(".png", draw_model(grays[m], models[m]), png);
    } catch (const cv::Exception&) {
      encoded = false;
    }
    if (!encoded) return {StatusCode::kIoError, "--draw-model: cannot write " + target};
    if (Status s = out.add(target, png.data(), png.size()); !s)
      return {s.code(), "--draw-model " + s.message()};
  }
  return out.commit();
}

// Whether a MODEL argument names a set of models (a directory, or a
// models.json) rather than one image.
bool is_model_set(const std::string& arg) {
  std::error_code ec;
  return std::filesystem::is_directory(arg, ec) ||
         std::filesystem::path(arg).extension() == ".json";
}

// The model images as the builder gets them, when --max-side is given:
// loaded here (ROI and downsampling applied), then handed out by
// prepared_image(), the loader build_model_set() calls (a plain function).
std::map<std::string, cv::Mat> g_prepared;

Status prepared_image(const std::string& key, cv::Mat& gray) {
  const auto it = g_prepared.find(key);
  if (it == g_prepared.end()) return {StatusCode::kNotFound, key + ": not loaded"};
  gray = it->second;
  return Status::ok();
}

// Loads each source with load_model_photo(), cuts its ROI (given in the
// file's pixels, so scaled when the photo was decoded reduced) and
// downsamples it to `max_side` on its long edge; the sources then name
// their prepared image and carry no ROI.
Status prepare_model_images(std::vector<ModelSource>& sources, int max_side) {
  g_prepared.clear();
  for (ModelSource& source : sources) {
    cv::Mat gray;
    int scale = 1;
    if (Status s = load_model_photo(source.path, gray, scale); !s) return s;
    std::string key = source.path;
    if (source.roi) {
      const cv::Rect r = *source.roi;
      const cv::Rect scaled(r.x / scale, r.y / scale, std::max(1, r.width / scale),
                            std::max(1, r.height / scale));
      if (std::int64_t{r.x} + r.width > std::int64_t{gray.cols} * scale ||
          std::int64_t{r.y} + r.height > std::int64_t{gray.rows} * scale ||
          (scaled & cv::Rect(0, 0, gray.cols, gray.rows)) != scaled)
        return {StatusCode::kInvalidArgument,
                "ROI " + std::to_string(r.x) + "," + std::to_string(r.y) + "," +
                    std::to_string(r.width) + "," + std::to_string(r.height) + " lies outside " +
                    source.path};
      gray = gray(scaled).clone();
      key += " (ROI " + std::to_string(r.x) + "," + std::to_string(r.y) + "," +
             std::to_string(r.width) + "," + std::to_string(r.height) + ")";
    }
    const int long_side = std::max(gray.cols, gray.rows);
    if (long_side > max_side) {
      const double f = static_cast<double>(max_side) / long_side;
      cv::Mat smaller;
      cv::resize(gray, smaller,
                 cv::Size(std::max(1, static_cast<int>(std::lround(gray.cols * f))),
                          std::max(1, static_cast<int>(std::lround(gray.rows * f)))),
                 0, 0, cv::INTER_AREA);
      gray = smaller;
    }
    g_prepared[key] = gray;
    source.path = key;
    source.roi.reset();
  }
  return Status::ok();
}

// The --preset of `args` (before `--`), found before the options are
// parsed so that it applies under every other option whatever the order;
// empty when none is given.
std::string preset_argument(const Args& args) {
  std::string name;
  for (std::size_t i = 0; i + 1 < args.size() && args[i] != "--"; ++i) {
    if (args[i] == "--preset") name = args[++i];
  }
  return name;
}

// load_image() with a hint for photos over the pixel limit.
Status load_model_image_or_hint(const std::string& path, cv::Mat& gray) {
  Status s = load_image(path, gray);
  if (s.code() != StatusCode::kResourceExhausted) return s;
  return {s.code(), s.message() + "; --max-side PX (e.g. --max-side 2000) downsamples it"};
}

}  // namespace

int cmd_build(const Args& args) {
  // The MODEL arguments in order: an image, or a set (directory, models.json).
  struct ModelArgument {
    bool set;
    ModelSource source;
  };
  std::vector<ModelArgument> arguments;
  std::optional<cv::Rect> pending_roi;
  std::optional<std::string> pending_name;
  std::string output, draw_dir;
  int max_side = 0;
  bool look_alikes = true;
  Params params;
  if (const std::string preset = preset_argument(args); !preset.empty()) {
    Params preset_set;
    // An unknown name is reported by the --preset option below.
    if (preset_params(preset, preset_set)) params = preset_set;
  }
  bool tilt_given = false, tilt_levels_given = false;
  bool quiet = false;
  int jobs = 0;
  // A value of `params` (the defaults of the options below) as text.
  auto param_text = [&params](const char* name) {
    std::string text;
    param_value_text(params, name, text);  // empty (no default shown) for an unknown name
    return text;
  };
  Options table("build", "[options] [--name NAME] [--roi X,Y,W,H] MODEL... -o OUT.kgi",
                "Compiles model images (signs, posters, any planar object) into one index.\n"
                "--name and --roi apply to the MODEL that follows them.");
  table
      .positional("MODEL...",
                  "model image files (PNG, JPEG, ...): one model each; or a directory (each\n"
                  "image in it a model, or its models.json) or a models.json (docs/EVAL.md)",
                  [&](const std::string& v) -> std::string {
                    if (is_model_set(v)) {
                      if (pending_name || pending_roi)
                        return "--name and --roi apply to one model image, not to " + v;
                      arguments.push_back({true, {{}, v, std::nullopt}});
                      return {};
                    }
                    arguments.push_back(
                        {false,
                         {pending_name ? *pending_name : std::filesystem::path(v).stem().string(),
                          v, pending_roi}});
                    pending_roi.reset();
                    pending_name.reset();
                    return {};
                  })
      .text("-o, --out, --output", "OUT.kgi", output, "the index to write (required)")
      .value("--name", "NAME", "the next MODEL's name (default: its file name without extension)",
             [&pending_name](const std::string& v) -> std::string {
               if (pending_name) return "two --name options for one model image";
               pending_name = v;
               return {};
             })
      .repeatable()
      .value("--roi", "X,Y,W,H",
             "the next MODEL is this rectangle of its image, in pixels\n"
             "(model pixel (0,0) is image pixel (X,Y); default: the whole image)",
             [&pending_roi](const std::string& v) -> std::string {
               cv::Rect roi;
               if (!parse_roi(v, roi)) return "--roi takes X,Y,W,H (pixels), got '" + v + "'";
               if (pending_roi) return "two --roi options for one model image";
               pending_roi = roi;
               return {};
             })
      .repeatable()
      .value(
          "--preset", "NAME",
          "start from a named parameter set instead of the defaults (every other\n"
          "option applies over it, wherever it is given): defaults; frontal: no tilted\n"
          "views, no triangle check or circuit completion, arcs between every pair in\n"
          "range, 20 search leaves (the cheapest frame, for objects seen face on);\n"
          "angled: tilts to 60 degrees in two levels, arcs between every pair in range,\n"
          "10 search leaves (a little more recall at an angle for about 1.5x the frame)",
          [](const std::string& v) -> std::string {
            Params unused;
            if (Status s = preset_params(v, unused); !s)
              return "--preset " + v + ": " + s.message();
            return {};
          },
          "defaults")
      .value(
          "--detector", "hessian|mser", "the keypoint detector",
          [&params](const std::string& v) -> std::string {
            if (!parse_enum(v.c_str(), params.keypoints.detector))
              return "unknown detector '" + v + "' (hessian or mser)";
            return {};
          },
          param_text("keypoints.detector"))
      .value(
          "--structure", "2|3|4", "keygraph structure: 2, 3 or 4 arcs per triangle",
          [&params](const std::string& v) -> std::string {
            if (v != "2" && v != "3" && v != "4") return "--structure takes 2, 3 or 4";
            params.graph.structure = static_cast<Structure>(v[0] - '0');
            return {};
          },
          param_text("graph.structure"))
      .value(
          "--vertex-descriptor", "none|sift",
          "sift: a SIFT descriptor per keypoint as well as per arc",
          [&params](const std::string& v) -> std::string {
            if (!parse_enum(v.c_str(), params.descriptor.vertex_descriptor))
              return "unknown vertex descriptor '" + v + "' (none or sift)";
            return {};
          },
          param_text("descriptor.vertex_descriptor"))
      .value(
          "--encoding", "float32|int16|int8", "how arc descriptors are stored in the index",
          [&params](const std::string& v) -> std::string {
            if (!parse_enum(v.c_str(), params.descriptor.encoding))
              return "unknown encoding '" + v + "' (float32, int16 or int8)";
            return {};
          },
          param_text("descriptor.encoding"))
      .value(
          "--min-size", "PX",
          "the smallest size, pixels on the long edge, at which a model must still be\n"
          "found: views are simulated down to it; 0: no views (views.min_size)",
          [&params](const std::string& v) -> std::string {
            if (Status s = set_param(params, "views.min_size=" + v); !s)
              return "--min-size: " + s.message();
            return {};
          },
          param_text("views.min_size"))
      .value(
          "--max-scale", "S",
          "the largest size, relative to the model image, at which a model must still\n"
          "be found: frontal views are simulated up to it; 1: none larger than the\n"
          "image (views.max_scale)",
          [&params](const std::string& v) -> std::string {
            if (Status s = set_param(params, "views.max_scale=" + v); !s)
              return "--max-scale: " + s.message();
            return {};
          },
          param_text("views.max_scale"))
      .value(
          "--max-tilt", "DEG",
          "the largest simulated out-of-plane tilt, degrees (0: frontal only); also sets\n"
          "the tilt levels in ASIFT's steps (1 to about 55, 2 to about 62) unless\n"
          "views.tilt_levels is --set (views.max_tilt)",
          [&params, &tilt_given](const std::string& v) -> std::string {
            if (Status s = set_param(params, "views.max_tilt=" + v); !s)
              return "--max-tilt: " + s.message();
            tilt_given = true;
            return {};
          },
          param_text("views.max_tilt"))
      .value("--set", "NAME=VALUE",
             "any parameter of keygraph/params.h\n"
             "(e.g. graph.max_keypoints=300; keygraph inspect lists them all)",
             [&params, &tilt_levels_given](const std::string& v) -> std::string {
               if (Status s = set_param(params, v); !s) return s.message();
               if (v.rfind("views.tilt_levels=", 0) == 0) tilt_levels_given = true;
               return {};
             })
      .repeatable()
      .integer("--max-side", "PX", max_side, 0, Limits::kMaxSide,
               "downsample each model image (after its ROI) to PX pixels on its long edge\n"
               "when larger, and decode JPEG photos over the pixel limit at 1/2, 1/4 or\n"
               "1/8 of their size first; 0: use the images as they are")
      .text("--draw-model", "DIR", draw_dir,
            "also write a picture of each model into DIR (MODEL.png: its keypoints\n"
            "and strongest keygraphs)")
      .flag("--no-look-alikes",
            "skip the look-alike check of the quality report (each model rendered as\n"
            "a scene and detected with the whole index)",
            [&look_alikes] { look_alikes = false; })
      .integer("-j, --jobs", "N", jobs, 0, 1024,
               "models built at once; 0: one per CPU this process may use (the index\n"
               "is the same for any N)")
      .flag("-q, --quiet", quiet,
            "no progress on stderr (by default one line rewritten in place on a\n"
            "terminal, otherwise a line per model)")
      .example("keygraph build --name exit --roi 10,10,200,120 exit.png stairs.png -o signs.kgi")
      .example("keygraph build --max-side 2000 photos/ -o signs.kgi")
      .example(
          "keygraph build --preset frontal --set descriptor.max_search_leaves=10 signs/ -o "
          "signs.kgi");
  if (const int exit_code = table.parse(args); exit_code >= 0) return exit_code;
  if (tilt_given && !tilt_levels_given)
    params.views.tilt_levels =
        params.views.max_tilt > 0.f ? asift_tilt_levels(params.views.max_tilt) : 0;
  // Parameters out of range are the command line's fault.
  if (Status s = format::validate_params(params); !s) return table.usage_error(s.message());
  if (pending_roi) return table.usage_error("--roi must come before the model image it applies to");
  if (pending_name)
    return table.usage_error("--name must come before the model image it applies to");
  if (arguments.empty()) return table.usage_error("no model images given");
  if (output.empty()) return table.usage_error("no output given (-o OUT.kgi)");
  // The models, each set read; its files and the sets themselves are inputs.
  std::vector<ModelSource> sources;
  std::vector<std::string> paths;
  for (ModelArgument& a : arguments) {
    paths.push_back(a.source.path);
    if (!a.set) {
      sources.push_back(std::move(a.source));
      continue;
    }
    std::vector<ModelSource> set;
    if (Status s = read_model_sources(a.source.path, set); !s) return fail(s.message());
    for (ModelSource& m : set) {
      paths.push_back(m.path);
      sources.push_back(std::move(m));
    }
  }

  // The output first: a device node, a directory or one of the model
  // images as -o fails before the build, and an interrupted build leaves
  // nothing behind (the temporary is removed on SIGINT and SIGTERM).
  platform::OutputFile out;
  if (Status s = out.create(output, paths); !s) return fail("-o " + s.message());
  // So is a --draw-model that cannot be a directory or holds a picture's
  // name in the way (made, and written, only when the build succeeds).
  if (!draw_dir.empty()) {
    platform::OutputSet pictures(draw_dir, paths);
    Status s = platform::check_output_directory(draw_dir);
    for (std::size_t i = 0; s && i < sources.size(); ++i)
      s = pictures.check(
          (std::filesystem::path(draw_dir) / picture_name(sources[i].name)).string());
    if (!s) return fail("--draw-model " + s.message());
  }

  if (max_side > 0) {
    if (Status s = prepare_model_images(sources, max_side); !s) return fail(s.message());
  }
  ModelBuildOptions options;
  options.params = params;
  options.threads = jobs;
  std::vector<cv::Mat> grays;
  std::vector<BuiltModel> models;
  ProgressReporter progress({"build", "model", is_terminal(stderr), true},
                            quiet ? nullptr : stderr);
  Status built =
      build_model_set(sources, options, max_side > 0 ? prepared_image : load_model_image_or_hint,
                      grays, models, progress.callback());
  g_prepared.clear();
  progress.finish();
  if (!built) return fail("build: " + built.message());
  // Each model's size alone: what it adds to an index.
  std::vector<std::size_t> alone(models.size(), 0);
  const Status sized = parallel_for_status(models.size(), jobs, [&](std::size_t m) {
    std::vector<std::uint8_t> bytes;
    const Status s = serialize_index({models[m]}, options.params, bytes);
    alone[m] = bytes.size();
    return s;
  });
  if (!sized) return fail("build: " + sized.message());
  for (std::size_t m = 0; m < models.size(); ++m) {
    const BuiltModel& model = models[m];
    std::printf("%s: %zu views, %zu keypoints, %zu arcs, %llu keygraphs, %.1f KB alone\n",
                model.name.c_str(), model.views.size(), model.keypoints.size(), model.arcs.size(),
                static_cast<unsigned long long>(model.keygraphs),
                static_cast<double>(alone[m]) / 1024.0);
  }
  QualityOptions quality_options;
  quality_options.look_alikes = look_alikes;
  quality_options.threads = jobs;
  QualityReport quality;
  if (Status s = measure_quality(models, grays, options.params, quality_options, quality); !s)
    return fail("build: " + s.message());
  // The report as inspect prints it: from the index's own bytes.
  std::vector<std::uint8_t> bytes;
  if (Status s = serialize_index(models, options.params, bytes, &quality); !s)
    return fail("build: " + s.message());
  std::unique_ptr<std::uint8_t[]> storage;
  ModelIndex index;
  if (Status s = view_aligned_copy(bytes, storage, index); !s) return fail("build: " + s.message());
  print_quality_report(index, false, stdout);
  if (!draw_dir.empty()) {
    if (Status s = draw_models(draw_dir, models, grays, paths); !s)
      return fail("build: " + s.message());
  }
  Status s = out.write(bytes.data(), bytes.size());
  if (s) s = out.commit();
  if (!s) return fail(s.message());
  std::printf("wrote %s (%s)\n", output.c_str(),
              counted(static_cast<long long>(models.size()), "model").c_str());
  return 0;
}

}  // namespace kg::cli
