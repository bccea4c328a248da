// keygraph bench: its options are the Options table below (keygraph bench --help).
// Loads the index and every frame once, then runs Detector::detect() N
// times on each frame and prints the time per stage (DetectStats) and in
// total (steady clock around detect()) as min / median / p90 / max, and the
// detector's workspace bytes. The timed loop is the device's per-frame path
// and nothing else: frames are in memory, the result list and the timing
// table are allocated before it, and no output happens inside it, so any
// heap use a profiler sees there is detect()'s own.
#include <algorithm>
#include <chrono>
#include <cinttypes>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include "cli/device/device_commands.h"
#include "cli/device/frame_output.h"
#include "cli/device/json.h"
#include "cli/device/options.h"
#include "core/description/descriptor_encoding.h"
#include "keygraph/detector.h"
#include "platform/convert.h"
#include "platform/files/file_source.h"

namespace kg::cli {

namespace {

using Clock = std::chrono::steady_clock;

struct LoadedFrame {
  std::string name;
  platform::GrayImage image;
};

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

// Every frame of `paths` (files or directories, in the file source's order)
// copied into memory. Returns an error message, or empty.
std::string load_frames(const std::vector<std::string>& paths, std::vector<LoadedFrame>& out) {
  platform::FileSource source(paths);
  if (Status s = source.start(); !s) return s.message();
  platform::Frame frame;
  for (Status s = source.next(frame, 0); !platform::is_end_of_stream(s);
       s = source.next(frame, 0)) {
    if (!s) return s.message();
    LoadedFrame& f = out.emplace_back();
    f.name = source.last_path();
    f.image.width = frame.image.width;
    f.image.height = frame.image.height;
    f.image.pixels.resize(static_cast<std::size_t>(frame.image.width) *
                          static_cast<std::size_t>(frame.image.height));
    platform::copy_gray(frame.image, f.image.pixels.data(), frame.image.width);
  }
  return {};
}

void print_text(const LoadedFrame& f, int repeat, int min_found, int max_found,
                const DetectStats& stats, const Summary (&rows)[kSeries]) {
  std::printf("\n%s (%dx%d), %d runs: ", f.name.c_str(), f.image.width, f.image.height, repeat);
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

void print_json(const LoadedFrame& f, int repeat, int min_found, int max_found,
                std::optional<std::size_t> workspace, const Summary (&rows)[kSeries]) {
  std::string s =
      "{\"frame\": " + json_string(f.name) + ", \"width\": " + std::to_string(f.image.width) +
      ", \"height\": " + std::to_string(f.image.height) +
      ", \"repeat\": " + std::to_string(repeat) +
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
  Options options("bench", "--index I.kgi [--repeat N] [--json] FRAME...",
                  "Times Detector::detect() per stage on frames held in memory: min, median, p90\n"
                  "and max milliseconds of each stage and in total, and the workspace bytes.");
  options
      .positional("FRAME...", "image files or directories of them (in name order)",
                  [&paths](const std::string& v) {
                    paths.push_back(v);
                    return std::string();
                  })
      .text("--index", "I.kgi", index_path, "the model index to detect with (required)")
      .integer("--repeat", "N", repeat, 1, 1000000, "detect() runs per frame")
      .flag("--json", json, "one JSON object per frame on stdout instead of the table")
      .example("keygraph bench --index signs.kgi --repeat 50 frames/");
  if (const int exit_code = options.parse(args); exit_code >= 0) return exit_code;
  if (index_path.empty()) return options.usage_error("no index given (--index I.kgi)");
  if (paths.empty()) return options.usage_error("no frames given (image files or directories)");

  ModelIndex index;
  if (Status s = ModelIndex::read(index_path, index); !s) return fail(s.message());
  if (const std::string problem = core_detector_problem(index); !problem.empty())
    return fail("bench: " + index_path + ": " + problem);
  std::vector<LoadedFrame> frames;
  if (std::string error = load_frames(paths, frames); !error.empty())
    return fail("bench: " + error);

  // A frame beyond the detector's limits is skipped with a warning.
  const auto beyond = [](const LoadedFrame& f) {
    return f.image.width > Limits::kMaxSide || f.image.height > Limits::kMaxSide;
  };
  for (const LoadedFrame& f : frames) {
    if (beyond(f)) {
      std::fprintf(stderr,
                   "keygraph: bench: %s: frame %dx%d is beyond the detector's limits (%d pixels "
                   "a side), skipped\n",
                   f.name.c_str(), f.image.width, f.image.height, Limits::kMaxSide);
    }
  }
  frames.erase(std::remove_if(frames.begin(), frames.end(), beyond), frames.end());
  if (frames.empty()) return fail("bench: no frame within the detector's limits");
  // One workspace for the largest frame, allocated before any timing.
  int width = 1, height = 1;
  for (const LoadedFrame& f : frames) {
    width = std::max(width, f.image.view().width);
    height = std::max(height, f.image.view().height);
  }
  Detector detector(index, Limits{}.for_frame(width, height));
  if (!detector.status()) return fail("bench: " + detector.status().message());
  const std::optional<std::size_t> workspace = detector.workspace_bytes();
  DetectionList found;
  // One row per run: the five stages and the total, filled by the timed loop.
  std::vector<double> table(static_cast<std::size_t>(repeat) * 6);
  std::vector<double> series(static_cast<std::size_t>(repeat));

  if (!json) {
    std::printf("index %s: %s, %u arcs, %s descriptors; %s, %s each\n", index_path.c_str(),
                counted(index.model_count(), "model").c_str(), index.arc_count(),
                encoding_name(index.descriptor_encoding()),
                counted(static_cast<long long>(frames.size()), "frame").c_str(),
                counted(repeat, "run").c_str());
    std::printf("detector workspace: %zu bytes (frames up to %dx%d)\n", *workspace, width, height);
  }
  std::fflush(stdout);
  for (const LoadedFrame& f : frames) {
    const ImageView view = f.image.view();
    int min_found = 1 << 30, max_found = 0;
    // The timed loop: detect() and clock reads only.
    for (int r = 0; r < repeat; ++r) {
      const Clock::time_point t0 = Clock::now();
      const Status s = detector.detect(view, found);
      const Clock::time_point t1 = Clock::now();
      if (!s) return fail("bench: " + f.name + ": " + s.message());
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
      print_json(f, repeat, min_found, max_found, workspace, rows);
    } else {
      print_text(f, repeat, min_found, max_found, detector.stats(), rows);
    }
    std::fflush(stdout);
  }
  return 0;
}

}  // namespace kg::cli
