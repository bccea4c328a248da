// keygraph repeatability --dataset DIR [--subsets a,b] [--detectors D,...]
//                        [--set NAME=VALUE]... [--max-keypoints N] [--tolerance PX]
//                        [--csv FILE]
//
// Keypoint detector repeatability on the Oxford layout (img1 against
// img2..img6 under the ground-truth homographies), keypoints per image,
// scene triangles that can be correct keygraphs and detection time per
// image on one thread (build/repeatability.h).
#include <cstdio>
#include <exception>
#include <filesystem>
#include <sstream>
#include <string>

#include <opencv2/core/utility.hpp>

#include "build/param_overrides.h"
#include "build/repeatability.h"
#include "build/repeatability_report.h"
#include "build/report_io.h"
#include "cli/commands.h"
#include "core/index_format.h"

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
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (i + 1 >= args.size()) return fail("repeatability: " + a + " needs a value (or is unknown)");
    const std::string& v = args[++i];
    if (a == "--dataset") {
      options.dataset = v;
    } else if (a == "--subsets") {
      options.subsets = split(v);
    } else if (a == "--detectors") {
      detectors = split(v);
    } else if (a == "--set") {
      if (Status s = apply_param_override(v, params); !s)
        return fail("repeatability: " + s.message());
    } else if (a == "--max-keypoints") {
      if (!parse_int(v, 1, 1 << 24, options.limits.max_keypoints))
        return fail("repeatability: bad --max-keypoints '" + v + "'");
    } else if (a == "--tolerance") {
      std::size_t used = 0;
      try {
        options.tolerance = std::stod(v, &used);
      } catch (const std::exception&) {
        used = 0;
      }
      if (used == 0 || used != v.size() || !(options.tolerance > 0 && options.tolerance <= 100))
        return fail("repeatability: bad --tolerance '" + v + "' (pixels, 0 < PX <= 100)");
    } else if (a == "--csv") {
      csv = v;
    } else {
      return fail("repeatability: unknown option " + a);
    }
  }
  if (options.dataset.empty()) return fail("repeatability: --dataset DIR is required");
  if (Status s = format::validate_params(params); !s) return fail("repeatability: " + s.message());
  if (detectors.empty()) return fail("repeatability: --detectors is empty");
  // A CSV that cannot be written fails now, not after the run.
  if (!csv.empty()) {
    const std::filesystem::path parent = std::filesystem::path(csv).parent_path();
    std::error_code ec;
    if (!parent.empty() && !std::filesystem::is_directory(parent, ec))
      return fail("repeatability: " + parent.string() + ": no such directory (for --csv)");
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
  Status s = evaluate_repeatability(options, cases, timings, print_progress);
  clear_progress();
  if (!s) return fail("repeatability: " + s.message());
  std::fputs(repeatability_text(cases, timings, options).c_str(), stdout);
  if (!csv.empty()) {
    if (s = write_text_file(csv, repeatability_csv(cases, timings)); !s)
      return fail("repeatability: " + s.message());
  }
  return 0;
}

}  // namespace kg::cli
