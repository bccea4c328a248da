// keygraph bench: its options are the Options table below (keygraph bench --help).
// Loads the index, then reads the frames one at a time (memory does not
// grow with their count): runs Detector::detect() N times on each and
// prints the time per stage (DetectStats) and in total (steady clock around
// detect()) as min / median / p90 / max, and the detector's workspace
// bytes. The timed loop is the device's per-frame path and nothing else:
// the frame is in memory, the workspace sized for it, the result list and
// the timing table are allocated before it, and no output happens inside
// it, so any heap use a profiler sees there is detect()'s own.
#include <algorithm>
#include <chrono>
#include <cinttypes>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include "cli/device/detector_fit.h"
#include "cli/device/device_commands.h"
#include "cli/device/frame_output.h"
#include "cli/device/json.h"
#include "cli/device/options.h"
#include "core/description/descriptor_encoding.h"
#include "keygraph/detector.h"
#include "platform/files/file_source.h"

namespace kg::cli {

namespace {

using Clock = std::chrono::steady_clock;

// The rows of the table: the core's stages, then the total and the part of
// the total outside the stages.
constexpr int kSeries = 7;
constexpr const char* kSeriesNames[kSeries] = {"keypoints", "graph", "describe", "select",
                                               "pose",      "total", "other"};

struct Summary {
  double min = 0, median = 0, p90 = 0, max = 0;
};

// Nearest-rank percentiles of `values` (reordered).
Summary summarize(std::vector<double>& values) {
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  auto rank = [&](double q) {
    const auto r = static_cast<std::size_t>(q * static_cast<double>(n) + 0.999999);
    return values[std::clamp<std::size_t>(r, 1, n) - 1];
  };
  return {values.front(), rank(0.5), rank(0.9), values.back()};
}

void print_text(const std::string& name, ImageView frame, int repeat, int min_found, int max_found,
                const DetectStats& stats, const Summary (&rows)[kSeries]) {
  std::printf("\n%s (%dx%d), %d runs: ", name.c_str(), frame.width, frame.height, repeat);
  if (min_found == max_found) {
    std::printf("%d detection(s) in every run", min_found);
  } else {
    std::printf("%d to %d detections", min_found, max_found);
  }
  std::printf("; %d keypoints, %d sampled, %d keygraphs, %d correspondences\n", stats.keypoints,
              stats.sampled_keypoints, stats.keygraphs, stats.correspondences);
  if (stats.completion_tried > 0) {
    std::printf(
        "  circuit completion: %lld model triples joined, %lld clockwise, %lld plausible, "
        "%lld closed\n",
        stats.completion_tried, stats.completion_clockwise, stats.completion_plausible,
        stats.completion_closed);
  }
  std::printf("  %-10s %9s %9s %9s %9s\n", "ms", "min", "median", "p90", "max");
  for (int i = 0; i < kSeries; ++i) {
    std::printf("  %-10s %9.3f %9.3f %9.3f %9.3f\n", kSeriesNames[i], rows[i].min, rows[i].median,
                rows[i].p90, rows[i].max);
  }
}

void print_json(const std::string& name, ImageView frame, int repeat, int threads, int min_found,
                int max_found, std::optional<std::size_t> workspace,
                const Summary (&rows)[kSeries]) {
  std::string s =
      "{\"frame\": " + json_string(name) + ", \"width\": " + std::to_string(frame.width) +
      ", \"height\": " + std::to_string(frame.height) + ", \"repeat\": " + std::to_string(repeat) +
      ", \"threads\": " + std::to_string(threads) +
      ", \"workspace_bytes\": " + (workspace ? std::to_string(*workspace) : std::string("null")) +
      ", \"detections\": {\"min\": " + std::to_string(min_found) +
      ", \"max\": " + std::to_string(max_found) + "}, \"ms\": {";
  for (int i = 0; i < kSeries; ++i) {
    s += std::string(i ? ", " : "") + "\"" + kSeriesNames[i] +
         "\": {\"min\": " + json_number(rows[i].min) +
         ", \"median\": " + json_number(rows[i].median) + ", \"p90\": " + json_number(rows[i].p90) +
         ", \"max\": " + json_number(rows[i].max) + "}";
  }
  std::printf("%s}}\n", s.c_str());
}

}  // namespace

int cmd_bench(const Args& args) {
  std::string index_path;
  int repeat = 20;
  bool json = false;
  std::vector<std::string> paths;
  DetectSettings settings;
  Options options("bench",
                  "--index I.kgi [--repeat N] [--json] [--set NAME=VALUE]... [--threads N]\n"
                  "       FRAME...",
                  "Times Detector::detect() per stage on each frame in memory: min, median, p90\n"
                  "and max milliseconds of each stage and in total, and the workspace bytes.");
  options
      .positional("FRAME...", "image files or directories of them (in name order)",
                  [&paths](const std::string& v) {
                    paths.push_back(v);
                    return std::string();
                  })
      .text("--index", "I.kgi", index_path, "the model index to detect with (required)")
      .integer("--repeat", "N", repeat, 1, 1000000, "detect() runs per frame")
      .flag("--json", json, "one JSON object per frame on stdout instead of the table");
  settings.declare(options);
  options.example("keygraph bench --index signs.kgi --repeat 50 frames/")
      .example("keygraph bench --index signs.kgi --threads 2 frames/");
  if (const int exit_code = options.parse(args); exit_code >= 0) return exit_code;
  if (index_path.empty()) return options.usage_error("no index given (--index I.kgi)");
  if (paths.empty()) return options.usage_error("no frames given (image files or directories)");

  ModelIndex index;
  if (Status s = ModelIndex::read(index_path, index); !s) return fail(s.message());
  if (const std::string problem = core_detector_problem(index); !problem.empty())
    return fail("bench: " + index_path + ": " + problem);
  platform::FileSource source(paths);
  if (Status s = source.start(); !s) return fail("bench: " + s.message());
  // The workspace for 640x480, grown when a frame does not fit
  // (fit_detector()), before that frame's timed loop.
  DetectOptions runtime;
  if (Status s = settings.options_for(index, runtime); !s) return options.usage_error(s.message());
  Detector detector(index, settings.limits(), runtime);
  if (!detector.status()) return fail("bench: " + detector.status().message());
  DetectionList found;
  // One row per run: the five stages and the total, filled by the timed loop.
  std::vector<double> table(static_cast<std::size_t>(repeat) * 6);
  std::vector<double> series(static_cast<std::size_t>(repeat));

  if (!json) {
    std::printf("index %s: %s, %u arcs, %s descriptors; %s, %s each, %s\n", index_path.c_str(),
                counted(index.model_count(), "model").c_str(), index.arc_count(),
                encoding_name(index.descriptor_encoding()),
                counted(static_cast<long long>(source.files().size()), "frame file").c_str(),
                counted(repeat, "run").c_str(), counted(settings.threads(), "thread").c_str());
  }
  std::fflush(stdout);
  std::optional<std::size_t> printed_workspace;
  int measured = 0;
  // Skipped frames not yet shown: the first few reasons, and how many.
  constexpr std::size_t kHeldReasons = 8;
  std::vector<std::string> skipped;
  std::size_t skipped_count = 0;
  const auto warn_skipped = [&] {
    for (const std::string& why : skipped)
      std::fprintf(stderr, "keygraph: bench: %s\n", one_line(why + ", skipped").c_str());
    if (skipped_count > skipped.size())
      std::fprintf(stderr, "keygraph: bench: %zu more frames skipped\n",
                   skipped_count - skipped.size());
    skipped.clear();
    skipped_count = 0;
  };
  platform::Frame frame;
  for (Status s = source.next(frame, 0); !platform::is_end_of_stream(s);
       s = source.next(frame, 0)) {
    if (!s) return fail("bench: " + s.message());
    const std::string name = source.last_path();
    const ImageView view = frame.image;
    // A frame the detector cannot take is skipped with a warning (held
    // until a frame is measured: without one, the error line says why).
    if (const Status fit = fit_detector(detector, view); !fit) {
      if (skipped.size() < kHeldReasons) skipped.push_back(name + ": " + fit.message());
      ++skipped_count;
      if (measured > 0) warn_skipped();
      continue;
    }
    if (measured == 0) warn_skipped();
    const std::optional<std::size_t> workspace = detector.workspace_bytes();
    if (!json && workspace != printed_workspace) {
      std::printf("detector workspace: %zu bytes (frames up to %dx%d)\n", workspace.value_or(0),
                  detector.limits().max_width, detector.limits().max_height);
      printed_workspace = workspace;
    }
    int min_found = 1 << 30, max_found = 0;
    // The timed loop: detect() and clock reads only.
    for (int r = 0; r < repeat; ++r) {
      const Clock::time_point t0 = Clock::now();
      const Status d = detector.detect(view, found);
      const Clock::time_point t1 = Clock::now();
      if (!d) return fail("bench: " + name + ": " + d.message());
      const DetectStats& st = detector.stats();
      double* row = &table[static_cast<std::size_t>(r) * 6];
      row[0] = st.ms_keypoints;
      row[1] = st.ms_graph;
      row[2] = st.ms_describe;
      row[3] = st.ms_select;
      row[4] = st.ms_pose;
      row[5] = std::chrono::duration<double, std::milli>(t1 - t0).count();
      const int n = static_cast<int>(found.size());
      min_found = std::min(min_found, n);
      max_found = std::max(max_found, n);
    }
    Summary rows[kSeries];
    for (int i = 0; i < kSeries; ++i) {
      for (int r = 0; r < repeat; ++r) {
        const double* row = &table[static_cast<std::size_t>(r) * 6];
        series[static_cast<std::size_t>(r)] =
            i < 6 ? row[i] : row[5] - (row[0] + row[1] + row[2] + row[3] + row[4]);
      }
      rows[i] = summarize(series);
    }
    if (json) {
      print_json(name, view, repeat, detector.limits().threads, min_found, max_found, workspace,
                 rows);
    } else {
      print_text(name, view, repeat, min_found, max_found, detector.stats(), rows);
    }
    std::fflush(stdout);
    ++measured;
  }
  if (measured == 0) {
    std::string why;
    if (skipped_count == 1) why = " (" + skipped.front() + ")";
    if (skipped_count > 1)
      why = " (" + std::to_string(skipped_count) + " frames; the first: " + skipped.front() + ")";
    return fail("bench: no frame within the detector's limits" + why);
  }
  return 0;
}

}  // namespace kg::cli
