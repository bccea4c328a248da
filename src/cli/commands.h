// The desktop keygraph subcommands (OpenCV, the model builder) and their
// image helpers. The commands that need no OpenCV are in
// cli/device/device_commands.h. Each returns the process exit code and
// reports any failure as one line on stderr.
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "cli/device/command_line.h"
#include "cli/device/options.h"
#include "eval/truth_eval.h"
#include "eval/video_eval.h"
#include "keygraph/detector.h"
#include "keygraph/status.h"

namespace kg::cli {

int cmd_build(const Args& args);
int cmd_detect(const Args& args);
int cmd_demo(const Args& args);
int cmd_eval(const Args& args);
int cmd_eval_truth(const Args& args);  // eval --truth (cmd_eval passes it on)
int cmd_eval_video(const Args& args);  // eval --video (cmd_eval passes it on)
// The options of eval --truth, bound to `options` and `out_dir`.
Options truth_options(TruthEvalOptions& options, std::string& out_dir, bool& quiet);
// The options of eval --video (cmd_eval_video.cpp).
Options video_options(VideoEvalOptions& options, bool& json, bool& quiet);
int cmd_manifest(const Args& args);
// The --methods option of eval: every name checked (a usage error names
// the unknown one); `given` (may be null) is set when the option is used.
Options::Apply method_list_option(std::vector<std::string>& methods, bool* given);
// eval's --set NAME=VALUE and --threads N on `options`: --set takes a
// parameter of the indexes eval builds (into `params`; `params_set`, when
// not null, is set) or a runtime option no index stores (min_confidence,
// time_budget_ms: into `detector`); --threads is the keygraph detectors'.
void declare_eval_settings(Options& options, Params& params, DetectorSettings& detector,
                           bool* params_set, const std::string& set_help);
int cmd_synth(const Args& args);
int cmd_repeatability(const Args& args);

// load_gray() with image decoders' own stderr output held back when the
// load fails, so the failure is reported as one line.
Status load_image(const std::string& path, cv::Mat& gray);
// The same file in colour (BGR; a gray file as three equal channels), with
// the same checks, for pictures of what was found.
Status load_color(const std::string& path, cv::Mat& bgr);
// A model photo for keygraph build: load_image(), except that a JPEG over
// the pixel limit is decoded at 1/2, 1/4 or 1/8 of its size (libjpeg scales
// while decoding: the full image is never in memory), the first that fits;
// `scale` is then 2, 4 or 8, else 1. An image over the limit that is not a
// JPEG stays an error, with a hint.
Status load_model_photo(const std::string& path, cv::Mat& gray, int& scale);

// The scene with each detection's outline and model name in colour (a
// colour scene stays in colour); names stay inside the picture.
cv::Mat draw_scene(const cv::Mat& scene, const DetectionList& found);
// Writes an image through a platform::OutputFile (a unique temporary
// renamed into place: no partial output, never over a non-regular file or
// one of `inputs`).
bool write_image_atomically(const std::string& path, const cv::Mat& image,
                            const std::vector<std::string>& inputs, std::string& error);

}  // namespace kg::cli
