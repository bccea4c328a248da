// keygraph repeatability: its options are the Options table below (keygraph repeatability --help).
//
// Keypoint detector repeatability on the Oxford layout (img1 against
// img2..img6 under the ground-truth homographies), keypoints per image,
// scene triangles that can be correct keygraphs and detection time per
// image on one thread (eval/repeatability.h).
#include <cstdio>
#include <exception>
#include <filesystem>
#include <sstream>
#include <string>

#include <opencv2/core/utility.hpp>

#include "cli/commands.h"
#include "cli/device/options.h"
#include "core/index/index_format.h"
#include "eval/repeatability.h"
#include "eval/repeatability_report.h"
#include "eval/report_io.h"
#include "keygraph/param_text.h"

namespace kg::cli {

namespace {

bool progress_shown = false;

void print_progress(const std::string& detector, const std::string& subset) {
  progress_shown = true;
  std::fprintf(stderr, "\r%-50.50s %-10.10s", detector.c_str(), subset.c_str());
}

void clear_progress() {
  if (progress_shown) std::fprintf(stderr, "\r%62s\r", "");
  progress_shown = false;
}

std::vector<std::string> split(const std::string& v) {
  std::vector<std::string> out;
  std::stringstream in(v);
  for (std::string s; std::getline(in, s, ',');) out.push_back(s);
  return out;
}

}  // namespace

int cmd_repeatability(const Args& args) {
  RepeatabilityOptions options;
  Params params;
  std::vector<std::string> detectors = {"hessian", "mser", "sift", "orb", "akaze"};
  std::string csv;
  bool quiet = false;
  Options table("repeatability",
                "--dataset DIR [--subsets a,b] [--detectors D,...] [--set NAME=VALUE]...\n"
                "       [--max-keypoints N] [--tolerance PX] [--csv FILE] [-q]",
                "Keypoint repeatability img1 -> img2..img6 on the Oxford layout (ground-truth\n"
                "homographies), keypoints per image, scene triangles that can be correct\n"
                "keygraphs, and detection time per image on one thread.");
  table.text("--dataset", "DIR", options.dataset, "the Oxford-layout set (required)")
      .value("--subsets", "a,b,...", "the subsets to use (default: every one with img1)",
             [&options](const std::string& v) {
               options.subsets = split(v);
               return std::string();
             })
      .value(
          "--detectors", "D,...",
          "keypoint detectors: hessian|mser[:NAME=VALUE...], sift, orb, akaze",
          [&detectors](const std::string& v) {
            detectors = split(v);
            return std::string();
          },
          "hessian,mser,sift,orb,akaze")
      .value("--set", "NAME=VALUE", "a parameter of keygraph/params.h",
             [&params](const std::string& v) {
               const Status s = set_param(params, v);
               return s ? std::string() : s.message();
             })
      .repeatable()
      .integer("--max-keypoints", "N", options.limits.max_keypoints, 1, 1 << 24,
               "keypoints per image at most")
      .number("--tolerance", "PX", options.tolerance, 0, 100, true,
              "a keypoint is repeated within this many pixels")
      .text("--csv", "FILE", csv, "also write every case to FILE")
      .flag("-q, --quiet", quiet,
            "no progress on stderr (by default the detector and subset being measured,\n"
            "rewritten in place)")
      .example("keygraph repeatability --dataset ../shared/data/oxford --detectors hessian,sift");
  if (const int exit_code = table.parse(args); exit_code >= 0) return exit_code;
  if (options.dataset.empty()) return table.usage_error("--dataset DIR is required");
  // Parameters out of range (--set) are the command line's fault.
  if (Status s = format::validate_params(params); !s) return table.usage_error(s.message());
  if (detectors.empty()) return table.usage_error("--detectors is empty");
  // A CSV that cannot be written fails now, not after the run (and never
  // replaces a file of the data set).
  const std::vector<std::string> inputs = files_under(options.dataset, 2);
  platform::OutputSet outputs(std::filesystem::path(csv).parent_path().string(), inputs);
  if (!csv.empty()) {
    const std::filesystem::path parent = std::filesystem::path(csv).parent_path();
    std::error_code ec;
    if (!parent.empty() && !std::filesystem::is_directory(parent, ec))
      return fail("repeatability: " + parent.string() + ": no such directory (for --csv)");
    if (Status s = outputs.check(csv); !s) return fail("repeatability: --csv " + s.message());
  }
  for (const std::string& d : detectors) {
    RepeatabilityDetector parsed;
    if (Status s = parse_repeatability_detector(d, params, parsed); !s)
      return fail("repeatability: " + s.message());
    options.detectors.push_back(parsed);
  }

  cv::setNumThreads(1);  // detection times on one thread, for every detector
  std::vector<RepeatabilityCase> cases;
  std::vector<DetectionTiming> timings;
  Status s = evaluate_repeatability(options, cases, timings, quiet ? nullptr : print_progress);
  clear_progress();
  if (!s) return fail("repeatability: " + s.message());
  std::fputs(repeatability_text(cases, timings, options).c_str(), stdout);
  if (!csv.empty()) {
    if (s = outputs.add(csv, repeatability_csv(cases, timings)); s) s = outputs.commit();
    if (!s) return fail("repeatability: " + s.message());
  }
  return 0;
}

}  // namespace kg::cli
