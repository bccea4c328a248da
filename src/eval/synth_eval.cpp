#include "eval/synth_eval.h"

#include <sys/stat.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <sstream>

#include <opencv2/imgproc.hpp>

#include "builder/desktop_detect.h"
#include "builder/image_io.h"
#include "builder/in_memory_index.h"
#include "builder/model_builder.h"
#include "eval/baselines.h"
#include "eval/correspondence_pr.h"
#include "eval/quad_geometry.h"
#include "eval/report_io.h"
#include "eval/synth/synth_set.h"

namespace kg {

namespace {

double median(std::vector<double> v) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

double scale_of(const SynthFrameInfo& info, const SynthSign* sign) {
  if (sign == nullptr || info.sign < 0) return 0;
  double area = 0;
  for (int i = 0; i < 4; ++i) {
    const Point2f& a = info.corners[i];
    const Point2f& b = info.corners[(i + 1) % 4];
    area += double{a.x} * b.y - double{b.x} * a.y;
  }
  return std::sqrt(std::abs(area) / 2 /
                   (static_cast<double>(sign->width - 1) * (sign->height - 1)));
}

// SynthCase::sign_keypoints and repeated_keypoints.
void count_sign_keypoints(ConstSpan<Keypoint> scene, const BuiltModel& model,
                          const SynthFrameInfo& truth, SynthCase& c) {
  std::vector<cv::Point2f> outline;
  for (const Point2f& p : truth.corners) outline.emplace_back(p.x, p.y);
  CorrespondenceTruth pairs;
  pairs.build(model.keypoints, scene.data(), static_cast<int>(scene.size()), truth.homography, 3.0);
  c.sign_keypoints = c.repeated_keypoints = 0;
  for (std::size_t i = 0; i < scene.size(); ++i) {
    if (cv::pointPolygonTest(outline, cv::Point2f(scene[i].x, scene[i].y), false) < 0) continue;
    ++c.sign_keypoints;
    c.repeated_keypoints += pairs.scene_repeated(static_cast<std::int32_t>(i));
  }
}

struct KeygraphMethod {
  std::string name;
  Params params;
  std::vector<BuiltModel> models;  // every sign
};

}  // namespace

void score_synth_frame(const std::vector<SynthDetection>& detections, const SynthFrameInfo& truth,
                       cv::Size sign_size, int group_begin, SynthCase& c) {
  c.detections = static_cast<int>(detections.size());
  c.false_detections = c.detections;
  c.found = c.found_iou = false;
  c.corner_error = -1;
  c.iou = 0;
  c.scored.clear();
  Point2f outline[4];
  if (truth.sign >= 0) sign_outline(sign_size, outline);
  double best = -1;
  for (const SynthDetection& d : detections) {
    SynthScoredDetection scored;
    scored.model = d.model;
    scored.support = d.detail;
    if (truth.sign >= 0 && d.model == truth.sign - group_begin) {
      double worst = 0;
      for (const Point2f& p : outline) {
        const Point2f g = kg::apply(truth.homography, p), e = kg::apply(d.homography, p);
        const double error = std::hypot(double{g.x} - e.x, double{g.y} - e.y);
        worst = std::isfinite(error) ? std::max(worst, error) : 1e9;
      }
      scored.corner_error = worst;
      scored.right = worst <= 10.0;
      if (best < 0 || worst < best) best = worst;
      Point2f found[4];
      for (int i = 0; i < 4; ++i) found[i] = kg::apply(d.homography, outline[i]);
      c.iou = std::max(c.iou, quad_iou(found, truth.corners));
    }
    c.scored.push_back(scored);
  }
  if (truth.sign < 0) return;
  c.corner_error = best;
  c.found = best >= 0 && best <= 10.0;
  c.found_iou = c.iou >= 0.5;
  if (c.found) --c.false_detections;
}

Status evaluate_synth(const SynthEvalOptions& options, std::vector<SynthCase>& cases,
                      const ProgressFn& progress) {
  cases.clear();
  SynthManifest manifest;
  Status s = read_manifest(options.directory, manifest);
  if (!s) return s;
  const int sign_count = static_cast<int>(manifest.signs.size());
  std::vector<cv::Mat> signs(manifest.signs.size());
  for (std::size_t i = 0; i < signs.size(); ++i) {
    if (s = load_gray(options.directory + "/" + manifest.signs[i].file, signs[i]); !s) return s;
    if (signs[i].cols != manifest.signs[i].width || signs[i].rows != manifest.signs[i].height)
      return {StatusCode::kCorruptData,
              manifest.signs[i].file + ": size differs from the manifest"};
  }
  const int frame_count =
      options.max_frames > 0
          ? std::min(options.max_frames, static_cast<int>(manifest.frames.size()))
          : static_cast<int>(manifest.frames.size());
  // The frames are read when they are searched (memory does not grow with
  // their count; 100000 frames took 30 GB); each is checked here to be a
  // regular file first, so a missing one fails before any work.
  for (int i = 0; i < frame_count; ++i) {
    const std::string path =
        options.directory + "/" + manifest.frames[static_cast<std::size_t>(i)].file;
    struct stat info {};
    if (::stat(path.c_str(), &info) != 0 || !S_ISREG(info.st_mode))
      return {StatusCode::kNotFound, path + ": no such frame file (named by the manifest)"};
  }

  cv::setNumThreads(1);  // every method on one thread
  std::vector<KeygraphMethod> keygraphs;
  std::vector<BaselineOptions> baselines;
  std::vector<std::string> baseline_methods;
  for (const std::string& m : options.methods) {
    BaselineOptions b;
    if (m == "keygraph" || m == "keygraph-mser") {
      KeygraphMethod k;
      k.name = m;
      k.params = options.params;
      if (m == "keygraph-mser") k.params.keypoints.detector = KeypointDetector::kMser;
      k.models.resize(signs.size());
      for (std::size_t i = 0; i < signs.size(); ++i) {
        s = build_model(signs[i], manifest.signs[i].name, k.params, k.models[i]);
        if (!s) return {s.code(), manifest.signs[i].file + ": " + s.message()};
      }
      keygraphs.push_back(std::move(k));
    } else if (parse_baseline(m, b)) {
      baselines.push_back(b);
      baseline_methods.push_back(m);
    } else {
      return {StatusCode::kInvalidArgument, "unknown method '" + m + "'"};
    }
  }

  std::vector<int> sizes;
  for (const int n : options.index_sizes) {
    const int capped = std::clamp(n, 1, sign_count);
    if (std::find(sizes.begin(), sizes.end(), capped) == sizes.end()) sizes.push_back(capped);
  }
  using Clock = std::chrono::steady_clock;
  // Cases: every frame, once per index size and method.
  const int total_cases = static_cast<int>(sizes.size()) * frame_count *
                          static_cast<int>(keygraphs.size() + baselines.size());
  for (const int n : sizes) {
    const int groups = (sign_count + n - 1) / n;
    std::vector<int> group_of(static_cast<std::size_t>(frame_count));
    int sign_free = 0;
    for (int f = 0; f < frame_count; ++f) {
      const int sign = manifest.frames[static_cast<std::size_t>(f)].info.sign;
      group_of[static_cast<std::size_t>(f)] = sign >= 0 ? sign / n : sign_free++ % groups;
    }
    for (int g = 0; g < groups; ++g) {
      const int begin = g * n, end = std::min(sign_count, begin + n);
      // The group's index for every method.
      std::vector<std::unique_ptr<InMemoryIndex>> indexes;
      std::vector<std::unique_ptr<DesktopDetector>> detectors;
      for (const KeygraphMethod& k : keygraphs) {
        indexes.push_back(std::make_unique<InMemoryIndex>());
        const std::vector<BuiltModel> models(k.models.begin() + begin, k.models.begin() + end);
        if (s = indexes.back()->build(models, k.params); !s) return s;
        detectors.push_back(
            std::make_unique<DesktopDetector>(indexes.back()->index(), Limits{}, options.detector));
      }
      std::vector<BaselineDetector> base;
      const std::vector<cv::Mat> group_signs(signs.begin() + begin, signs.begin() + end);
      for (const BaselineOptions& b : baselines) {
        base.emplace_back(b);
        base.back().set_models(group_signs);
      }
      for (int f = 0; f < frame_count; ++f) {
        if (group_of[static_cast<std::size_t>(f)] != g) continue;
        const SynthFrameEntry& entry = manifest.frames[static_cast<std::size_t>(f)];
        cv::Mat frame;
        if (s = load_gray(options.directory + "/" + entry.file, frame); !s) return s;
        const SynthSign* sign = entry.info.sign >= 0
                                    ? &manifest.signs[static_cast<std::size_t>(entry.info.sign)]
                                    : nullptr;
        for (std::size_t m = 0; m < keygraphs.size() + base.size(); ++m) {
          SynthCase c;
          c.index_size = n;
          c.group = g;
          c.frame = f;
          c.sign = entry.info.sign;
          c.scale = scale_of(entry.info, sign);
          c.long_edge = sign != nullptr ? longest_side(entry.info.corners) : 0;
          c.distance = entry.info.distance;
          c.occluded = entry.info.occluded;
          c.blur_sigma = entry.info.blur_sigma;
          c.motion_blur = entry.info.motion_blur;
          c.noise_sigma = entry.info.noise_sigma;
          std::vector<SynthDetection> found;
          const auto start = Clock::now();
          if (m < keygraphs.size()) {
            c.method = keygraphs[m].name;
            c.has_confidence = true;
            DetectionList list;
            s = detectors[m]->detect(frame, list);
            c.time_ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
            if (!s) return {s.code(), entry.file + ": " + s.message()};
            for (const Detection& d : list) found.push_back({d.model_id, d.homography, d});
            if (sign != nullptr) {
              count_sign_keypoints(detectors[m]->core().last_keypoints(),
                                   keygraphs[m].models[static_cast<std::size_t>(entry.info.sign)],
                                   entry.info, c);
            }
          } else {
            const std::size_t b = m - keygraphs.size();
            c.method = baseline_methods[b];
            std::vector<BaselineDetection> list;
            base[b].detect(frame, list);
            c.time_ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
            for (const BaselineDetection& d : list) {
              SynthDetection sd;
              sd.model = d.model_id;
              sd.homography = d.homography;
              sd.detail.inliers = d.inliers;
              found.push_back(sd);
            }
          }
          score_synth_frame(found, entry.info,
                            sign != nullptr ? cv::Size(sign->width, sign->height) : cv::Size(),
                            begin, c);
          cases.push_back(c);
          if (progress) {
            progress(static_cast<int>(cases.size()), total_cases,
                     c.method + ", index of " + std::to_string(n) + ", frame " + std::to_string(f));
          }
        }
      }
    }
  }
  return Status::ok();
}

std::vector<SynthRow> synth_tallies(const std::vector<SynthCase>& cases,
                                    const SynthEvalOptions& options) {
  std::vector<SynthRow> rows;
  std::vector<int> sizes;
  for (const SynthCase& c : cases) {
    if (std::find(sizes.begin(), sizes.end(), c.index_size) == sizes.end())
      sizes.push_back(c.index_size);
  }
  for (const int n : sizes) {
    for (const std::string& method : options.methods) {
      SynthRow r;
      r.method = method;
      r.index_size = n;
      std::vector<double> errors, times;
      for (const SynthCase& c : cases) {
        if (c.method != method || c.index_size != n) continue;
        ++r.frames;
        times.push_back(c.time_ms);
        r.false_detections += c.false_detections;
        if (c.sign < 0) {
          ++r.sign_free_frames;
          r.sign_free_with_false += c.detections > 0;
          continue;
        }
        ++r.sign_frames;
        r.within10 += c.found;
        r.within3 += c.found && c.corner_error <= 3.0;
        if (c.found) errors.push_back(c.corner_error);
      }
      if (r.frames == 0) continue;
      r.median_corner_error = median(errors);
      r.median_ms = median(times);
      double sum = 0;
      for (const double t : times) sum += t;
      r.mean_ms = sum / static_cast<double>(times.size());
      rows.push_back(r);
    }
  }
  return rows;
}

const std::vector<double>& synth_scale_buckets() {
  static const std::vector<double> b = {0.25, 0.35, 0.5, 0.7,
                                        std::numeric_limits<double>::infinity()};
  return b;
}

const std::vector<double>& synth_bin_bounds(SynthBinBy by) {
  static const double inf = std::numeric_limits<double>::infinity();
  static const std::vector<double> long_edge = {20, 30, 40, 60, 100, 160, inf};
  // A 30 cm sign at 640x480 (focal 600 px): 120, 72, 45, 30 and 20 px long.
  static const std::vector<double> distance = {1.5, 2.5, 4, 6, 9, inf};
  if (by == SynthBinBy::kLongEdge) return long_edge;
  if (by == SynthBinBy::kDistance) return distance;
  return synth_scale_buckets();
}

std::vector<SynthScaleRow> synth_by_scale(const std::vector<SynthCase>& cases,
                                          const SynthEvalOptions& options) {
  return synth_by_bins(cases, options, SynthBinBy::kScale);
}

std::vector<SynthScaleRow> synth_by_bins(const std::vector<SynthCase>& cases,
                                         const SynthEvalOptions& options, SynthBinBy by) {
  std::vector<SynthScaleRow> rows;
  if (cases.empty()) return rows;
  int smallest = cases[0].index_size;
  for (const SynthCase& c : cases) smallest = std::min(smallest, c.index_size);
  const std::vector<double>& b = synth_bin_bounds(by);
  for (const std::string& method : options.methods) {
    SynthScaleRow r{method,
                    smallest,
                    std::vector<int>(b.size(), 0),
                    std::vector<int>(b.size(), 0),
                    std::vector<int>(b.size(), 0),
                    std::vector<double>(b.size(), 0.0),
                    std::vector<double>(b.size(), 0.0)};
    std::vector<int> measured(b.size(), 0);
    for (const SynthCase& c : cases) {
      if (c.method != method || c.index_size != smallest || c.sign < 0) continue;
      const double v = by == SynthBinBy::kScale      ? c.scale
                       : by == SynthBinBy::kLongEdge ? c.long_edge
                                                     : c.distance;
      if (by == SynthBinBy::kDistance && !(v > 0)) continue;  // not recorded
      const auto k = static_cast<std::size_t>(std::lower_bound(b.begin(), b.end(), v) - b.begin());
      const std::size_t bucket = std::min(k, b.size() - 1);
      ++r.frames[bucket];
      r.found[bucket] += c.found;
      r.found_iou[bucket] += c.found_iou;
      if (c.sign_keypoints >= 0) {
        ++measured[bucket];
        r.keypoints[bucket] += c.sign_keypoints;
        r.repeated[bucket] += c.repeated_keypoints;
      }
    }
    for (std::size_t k = 0; k < b.size(); ++k) {
      const double n = measured[k];
      r.keypoints[k] = n > 0 ? r.keypoints[k] / n : std::nan("");
      r.repeated[k] = n > 0 ? r.repeated[k] / n : std::nan("");
    }
    rows.push_back(r);
  }
  return rows;
}

std::string synth_bins_text(const std::vector<SynthScaleRow>& rows, SynthBinBy by) {
  int any = 0;
  for (const SynthScaleRow& r : rows)
    for (const int n : r.frames) any += n;
  if (any == 0) return "";
  const std::vector<double>& b = synth_bin_bounds(by);
  std::string out;
  char line[256];
  const bool metres = by == SynthBinBy::kDistance;
  std::snprintf(line, sizeof(line),
                "\nFound within 10 px, and by IoU >= 0.5, by the sign's %s (index of %d)\n%-13s",
                metres ? "distance (m, a 30 cm sign)" : "long edge in the frame (px)",
                rows[0].index_size, metres ? "distance" : "long edge");
  out += line;
  double lo = 0;
  for (const double hi : b) {
    char label[32];
    if (std::isinf(hi)) {
      std::snprintf(label, sizeof(label), metres ? "%.1f+" : "%.0f+", lo);
    } else {
      std::snprintf(label, sizeof(label), metres ? "%.1f-%.1f" : "%.0f-%.0f", lo, hi);
    }
    std::snprintf(line, sizeof(line), " %17s", label);
    out += line;
    lo = hi;
  }
  out += "\n";
  for (const SynthScaleRow& r : rows) {
    std::snprintf(line, sizeof(line), "%-13s", r.method.c_str());
    out += line;
    for (std::size_t k = 0; k < b.size(); ++k) {
      char cell[48] = "-";  // a bin without frames has no rate
      if (r.frames[k] > 0)
        std::snprintf(cell, sizeof(cell), "%d/%d %d/%d", r.found[k], r.frames[k], r.found_iou[k],
                      r.frames[k]);
      std::snprintf(line, sizeof(line), " %17s", cell);
      out += line;
    }
    out += "\n";
  }
  return out;
}

const std::vector<double>& synth_confidence_thresholds() {
  static const std::vector<double> thresholds = {0.0, 0.5, 0.7, 0.8, 0.9};
  return thresholds;
}

std::vector<SynthConfidenceRow> synth_by_confidence(const std::vector<SynthCase>& cases) {
  std::vector<SynthConfidenceRow> rows;
  for (const SynthCase& c : cases) {
    if (!c.has_confidence) continue;  // baselines
    for (const double t : synth_confidence_thresholds()) {
      auto it = std::find_if(rows.begin(), rows.end(), [&](const SynthConfidenceRow& r) {
        return r.method == c.method && r.index_size == c.index_size && r.threshold == t;
      });
      if (it == rows.end()) {
        rows.push_back({c.method, c.index_size, t});
        it = rows.end() - 1;
      }
      ++it->frames;
      it->sign_frames += c.sign >= 0 ? 1 : 0;
      // As in the main table: every kept detection but one right one is false
      // (a second right detection of the same sign too).
      bool found = false;
      int kept = 0;
      for (const SynthScoredDetection& d : c.scored) {
        if (d.support.confidence < t) continue;
        ++kept;
        found = found || d.right;
      }
      it->found += found ? 1 : 0;
      it->false_detections += kept - (found ? 1 : 0);
    }
  }
  return rows;
}

std::string synth_text(const std::vector<SynthRow>& rows,
                       const std::vector<SynthScaleRow>& by_scale,
                       const std::vector<SynthConfidenceRow>& by_confidence) {
  std::string out;
  char line[256];
  std::snprintf(line, sizeof(line), "%-13s %5s %6s %8s %8s %9s %10s %11s %10s\n", "method", "index",
                "frames", "<=3px", "<=10px", "median px", "false/frm", "false-free", "median ms");
  out += line;
  for (const SynthRow& r : rows) {
    const double signs = std::max(1, r.sign_frames), frames = std::max(1, r.frames);
    // No sign found: no median corner error (a dash, not "nan").
    char median[16] = "-";
    if (!std::isnan(r.median_corner_error))
      std::snprintf(median, sizeof(median), "%.2f", r.median_corner_error);
    std::snprintf(line, sizeof(line), "%-13s %5d %6d %7.1f%% %7.1f%% %9s %10.3f %5d/%-5d %10.1f\n",
                  r.method.c_str(), r.index_size, r.frames, 100.0 * r.within3 / signs,
                  100.0 * r.within10 / signs, median, r.false_detections / frames,
                  r.sign_free_with_false, r.sign_free_frames, r.median_ms);
    out += line;
  }
  if (!by_confidence.empty()) {
    out += "\nKept at detection confidence >= threshold: signs found within 10 px, false / frame\n";
    std::snprintf(line, sizeof(line), "%-13s %5s", "method", "index");
    out += line;
    for (const double t : synth_confidence_thresholds()) {
      std::snprintf(line, sizeof(line), "   >= %.1f        ", t);
      out += line;
    }
    out += "\n";
    for (std::size_t i = 0; i < by_confidence.size();) {
      const SynthConfidenceRow& first = by_confidence[i];
      std::snprintf(line, sizeof(line), "%-13s %5d", first.method.c_str(), first.index_size);
      out += line;
      for (; i < by_confidence.size() && by_confidence[i].method == first.method &&
             by_confidence[i].index_size == first.index_size;
           ++i) {
        const SynthConfidenceRow& r = by_confidence[i];
        std::snprintf(line, sizeof(line), "  %5.1f%% %6.3f  ",
                      100.0 * r.found / std::max(1, r.sign_frames),
                      static_cast<double>(r.false_detections) / std::max(1, r.frames));
        out += line;
      }
      out += "\n";
    }
  }
  if (by_scale.empty()) return out;
  const std::vector<double>& b = synth_scale_buckets();
  std::snprintf(line, sizeof(line),
                "\nFound within 10 px by sign scale in the frame (index of %d)\n%-13s",
                by_scale[0].index_size, "scale");
  out += line;
  double lo = 0;
  for (const double hi : b) {
    std::snprintf(line, sizeof(line), std::isinf(hi) ? " %6.2f+      " : " %4.2f-%-4.2f  ", lo, hi);
    out += line;
    lo = hi;
  }
  out += "\n";
  for (const SynthScaleRow& r : by_scale) {
    std::snprintf(line, sizeof(line), "%-13s", r.method.c_str());
    out += line;
    for (std::size_t k = 0; k < b.size(); ++k) {
      // A bin without frames has no rate: a dash, not "0/0 0%".
      if (r.frames[k] > 0) {
        std::snprintf(line, sizeof(line), " %3d/%-3d %3.0f%%", r.found[k], r.frames[k],
                      100.0 * r.found[k] / r.frames[k]);
      } else {
        std::snprintf(line, sizeof(line), " %7s     ", "-");
      }
      out += line;
    }
    out += "\n";
  }
  bool any = false;
  for (const SynthScaleRow& r : by_scale) any = any || !std::isnan(r.keypoints.back());
  if (!any) return out;
  out +=
      "\nSampled keypoints on the sign, of them repeated (within 3 px of a model keypoint), mean\n";
  for (const SynthScaleRow& r : by_scale) {
    if (std::isnan(r.keypoints.back()) && std::isnan(r.keypoints.front())) continue;
    std::snprintf(line, sizeof(line), "%-13s", r.method.c_str());
    out += line;
    for (std::size_t k = 0; k < b.size(); ++k) {
      // An empty bin has no mean: dashes, not "nan nan".
      if (std::isnan(r.keypoints[k]) || std::isnan(r.repeated[k])) {
        std::snprintf(line, sizeof(line), " %5s %5s  ", "-", "-");
      } else {
        std::snprintf(line, sizeof(line), " %5.1f %5.1f  ", r.keypoints[k], r.repeated[k]);
      }
      out += line;
    }
    out += "\n";
  }
  return out;
}

Status write_synth_report(platform::OutputSet& out, const std::string& dir,
                          const SynthEvalOptions& options, const std::vector<SynthCase>& cases) {
  Status s;
  std::ostringstream csv;
  csv << "method,index_size,group,frame,sign,found,corner_error,detections,false_detections,"
         "time_ms,scale,occluded,blur_sigma,motion_blur,noise_sigma,sign_keypoints,"
         "repeated_keypoints,long_edge,distance,iou\n";
  for (const SynthCase& c : cases) {
    csv << c.method << ',' << c.index_size << ',' << c.group << ',' << c.frame << ',' << c.sign
        << ',' << c.found << ',' << c.corner_error << ',' << c.detections << ','
        << c.false_detections << ',' << c.time_ms << ',' << c.scale << ',' << c.occluded << ','
        << c.blur_sigma << ',' << c.motion_blur << ',' << c.noise_sigma << ',' << c.sign_keypoints
        << ',' << c.repeated_keypoints << ',' << c.long_edge << ',' << c.distance << ',' << c.iou
        << '\n';
  }
  if (s = out.add(dir + "/synth-cases.csv", csv.str()); !s) return s;
  // Every detection with its support, for precision-recall by confidence.
  std::ostringstream det;
  det << "method,index_size,frame,sign,model,right,corner_error,inliers,inlier_keygraphs,"
         "verification_z,score,chance,rms_error,appearance,confidence\n";
  for (const SynthCase& c : cases) {
    for (const SynthScoredDetection& d : c.scored) {
      det << c.method << ',' << c.index_size << ',' << c.frame << ',' << c.sign << ',' << d.model
          << ',' << d.right << ',' << d.corner_error << ',' << d.support.inliers << ','
          << d.support.inlier_keygraphs << ',' << d.support.verification_z << ',' << d.support.score
          << ',' << d.support.chance << ',' << d.support.rms_error << ',' << d.support.appearance
          << ',' << (c.has_confidence ? d.support.confidence : -1.0) << '\n';
    }
  }
  if (s = out.add(dir + "/synth-detections.csv", det.str()); !s) return s;
  const std::vector<SynthRow> rows = synth_tallies(cases, options);
  std::ostringstream j;
  j << "{\n  \"protocol\": \"synth\",\n  \"directory\": " << json_quote(options.directory)
    << ",\n  \"results\": [\n";
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const SynthRow& r = rows[i];
    j << "    {\"method\": " << json_quote(r.method) << ", \"index_size\": " << r.index_size
      << ", \"frames\": " << r.frames << ", \"sign_frames\": " << r.sign_frames
      << ", \"sign_free_frames\": " << r.sign_free_frames << ", \"within_3px\": " << r.within3
      << ", \"within_10px\": " << r.within10
      << ", \"median_corner_error_px\": " << json_value(r.median_corner_error)
      << ", \"false_detections\": " << r.false_detections
      << ", \"sign_free_frames_with_detections\": " << r.sign_free_with_false
      << ", \"median_ms\": " << json_value(r.median_ms)
      << ", \"mean_ms\": " << json_value(r.mean_ms) << "}" << (i + 1 < rows.size() ? ",\n" : "\n");
  }
  j << "  ],\n  \"by_confidence\": [\n";
  const std::vector<SynthConfidenceRow> confidence = synth_by_confidence(cases);
  for (std::size_t i = 0; i < confidence.size(); ++i) {
    const SynthConfidenceRow& r = confidence[i];
    j << "    {\"method\": " << json_quote(r.method) << ", \"index_size\": " << r.index_size
      << ", \"threshold\": " << r.threshold << ", \"frames\": " << r.frames
      << ", \"sign_frames\": " << r.sign_frames << ", \"within_10px\": " << r.found
      << ", \"false_detections\": " << r.false_detections << "}"
      << (i + 1 < confidence.size() ? ",\n" : "\n");
  }
  j << "  ]";
  // Per bin of long edge and of distance, the smallest index (as printed).
  for (const SynthBinBy by : {SynthBinBy::kLongEdge, SynthBinBy::kDistance}) {
    j << ",\n  \"" << (by == SynthBinBy::kLongEdge ? "by_long_edge_px" : "by_distance_m")
      << "\": [\n";
    const std::vector<double>& b = synth_bin_bounds(by);
    bool first = true;
    for (const SynthScaleRow& r : synth_by_bins(cases, options, by)) {
      for (std::size_t k = 0; k < b.size(); ++k) {
        if (r.frames[k] == 0) continue;
        j << (first ? "" : ",\n") << "    {\"method\": " << json_quote(r.method)
          << ", \"index_size\": " << r.index_size
          << ", \"from\": " << json_value(k == 0 ? 0.0 : b[k - 1])
          << ", \"to\": " << json_value(b[k]) << ", \"frames\": " << r.frames[k]
          << ", \"within_10px\": " << r.found[k] << ", \"iou_50\": " << r.found_iou[k] << "}";
        first = false;
      }
    }
    j << (first ? "" : "\n") << "  ]";
  }
  j << "\n}\n";
  return out.add(dir + "/synth-summary.json", j.str());
}

}  // namespace kg
