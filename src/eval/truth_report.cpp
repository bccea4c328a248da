#include "eval/truth_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <sstream>

#include "builder/image_io.h"
#include "eval/plot.h"
#include "eval/report_io.h"

namespace kg {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

const std::vector<double>& size_edges() {
  return truth_size_edges();
}
const std::vector<double>& scale_edges() {
  static const std::vector<double> e = {0, 0.1, 0.15, 0.2, 0.3, 0.5, 0.7, 1, 1.5, kInf};
  return e;
}

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  const auto i = static_cast<std::size_t>(std::ceil(q * static_cast<double>(v.size()))) - 1;
  return v[std::min(i, v.size() - 1)];
}

std::vector<TruthBin> bin_cases(const std::vector<const TruthCase*>& cases,
                                const std::vector<double>& edges, bool by_size) {
  std::vector<TruthBin> bins;
  for (std::size_t k = 0; k + 1 < edges.size(); ++k) {
    TruthBin b;
    b.lo = edges[k];
    b.hi = edges[k + 1];
    std::vector<double> sizes;
    for (const TruthCase* c : cases) {
      const double v = by_size ? c->long_edge : c->scale;
      if (!(v >= b.lo && v < b.hi)) continue;  // NaN in no bin
      ++b.instances;
      b.found += c->found;
      b.found_iou += c->found_iou;
      sizes.push_back(v);
      if (c->truth_refound < 0) continue;  // not measured
      ++b.measured;
      b.confirmable += c->truth_verifiable;
      b.some_matches += c->truth_matches > 0;
      b.enough_matches += c->truth_enough_matches;
      if (c->found_iou) continue;
      if (!c->truth_verifiable) {
        ++b.missed_keypoints;
      } else if (!c->truth_enough_matches) {
        ++b.missed_correspondences;
      } else {
        ++b.missed_pose;
      }
    }
    b.median_size = percentile(sizes, 0.5);
    bins.push_back(b);
  }
  return bins;
}

std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string out = "\"";
  for (const char c : s) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

std::string model_list(const TruthScene& scene, int instance) {
  if (instance < 0) return "";
  std::string out;
  for (const std::string& m : scene.instances[static_cast<std::size_t>(instance)].models)
    out += (out.empty() ? "" : "|") + m;
  return out;
}

std::string bin_label(const TruthBin& b, bool integer) {
  char text[32];
  if (std::isinf(b.hi)) {
    std::snprintf(text, sizeof(text), integer ? "%.0f+" : "%.2f+", b.lo);
  } else {
    std::snprintf(text, sizeof(text), integer ? "%.0f-%.0f" : "%.2f-%.2f", b.lo, b.hi);
  }
  return text;
}

std::string bins_json(const std::vector<TruthBin>& bins) {
  std::ostringstream j;
  j << "[";
  bool first = true;
  for (const TruthBin& b : bins) {
    if (b.instances == 0) continue;
    j << (first ? "" : ", ") << "{\"from\": " << json_value(b.lo)
      << ", \"to\": " << json_value(b.hi) << ", \"instances\": " << b.instances
      << ", \"found\": " << b.found << ", \"found_iou\": " << b.found_iou;
    if (b.measured > 0) {
      j << ", \"truth_measured\": " << b.measured << ", \"truth_confirmable\": " << b.confirmable
        << ", \"truth_some_matches\": " << b.some_matches
        << ", \"truth_enough_matches\": " << b.enough_matches
        << ", \"missed_keypoints\": " << b.missed_keypoints
        << ", \"missed_correspondences\": " << b.missed_correspondences
        << ", \"missed_pose\": " << b.missed_pose;
    }
    j << "}";
    first = false;
  }
  j << "]";
  return j.str();
}

}  // namespace

const std::vector<double>& truth_size_edges() {
  static const std::vector<double> e = {0, 20, 30, 40, 60, 100, 160, 256, 384, 512, 768, kInf};
  return e;
}

cv::Mat truth_size_plot(const std::vector<TruthRow>& rows) {
  PlotSpec spec;
  spec.title = "Found (all corners within the tolerance; dashed: IoU >= 0.5)";
  spec.x_label = "object long edge in the scene, log2 px (5 = 32 px, 7 = 128 px)";
  spec.y_label = "fraction found";
  spec.width = 900;
  spec.height = 480;
  double lo = kInf, hi = -kInf;
  // Series that find the same fraction would hide each other: each
  // (corners and IoU of every method) is shifted a little along x, at most
  // 0.1 either way (7 % in size), a method's line is drawn 4 pixels from
  // the next one's (a fraction of about 0.01), and it marks its points with
  // its own shape.
  const double series = 2.0 * static_cast<double>(rows.size());
  const double dodge = series > 1 ? 0.2 / (series - 1) : 0.0;
  const auto shift = [&](std::size_t k) {
    return (static_cast<double>(k) - (series - 1) / 2) * dodge;
  };
  for (std::size_t r = 0; r < rows.size(); ++r) {
    PlotSeries corners, iou;
    corners.label = rows[r].method;
    iou.label = rows[r].method + " (IoU)";
    corners.colour = iou.colour = plot_colour(static_cast<int>(r));
    corners.point_shape = iou.point_shape = static_cast<int>(r);
    corners.offset_y = iou.offset_y =
        4 * static_cast<int>(r) - 2 * (static_cast<int>(rows.size()) - 1);
    iou.dashed = true;
    for (const TruthBin& b : rows[r].by_size) {
      if (b.instances == 0) continue;
      // A step across the bin (half an octave past an open end), marked at
      // the bin's median size, then a break before the next bin.
      const double x = std::log2(std::max(b.median_size, 1.0));
      double left = x - 0.25, right = x + 0.25;  // a bin without bounds: around its median
      if (b.hi > b.lo) {
        left = b.lo > 0 ? std::log2(b.lo) : std::log2(std::min(b.hi, 1e9)) - 0.5;
        right = std::isinf(b.hi) ? std::log2(std::max(b.lo, 1.0)) + 0.5 : std::log2(b.hi);
      }
      left = std::min(left, x);
      right = std::max(right, x);
      lo = std::min(lo, left);
      hi = std::max(hi, right);
      const double fractions[2] = {static_cast<double>(b.found) / b.instances,
                                   static_cast<double>(b.found_iou) / b.instances};
      PlotSeries* both[2] = {&corners, &iou};
      for (std::size_t k = 0; k < 2; ++k) {
        PlotSeries& s = *both[k];
        const double d = shift(2 * r + k);
        for (const double px : {left + d, x + d, right + d, std::nan("")}) {
          s.x.push_back(px);
          s.y.push_back(fractions[k]);
          s.marked.push_back(px == x + d ? 1 : 0);
        }
      }
    }
    spec.series.push_back(corners);
    spec.series.push_back(iou);
  }
  if (!(lo <= hi)) lo = 4, hi = 8;
  spec.x_min = std::floor(lo - 0.1);
  spec.x_max = std::max(std::ceil(hi + 0.1), spec.x_min + 2);
  // Room below 0 and above 1: lines there are not drawn on the axes' box.
  spec.y_min = -0.05;
  spec.y_max = 1.05;
  spec.legend = LegendCorner::kOutsideRight;
  return render_plot(spec);
}

std::vector<TruthRow> truth_tallies(const TruthResults& results) {
  std::vector<TruthRow> rows;
  for (const std::string& method : results.methods) {
    TruthRow r;
    r.method = method;
    std::vector<double> times, errors, shown, refound;
    std::vector<const TruthCase*> instances;
    for (const TruthCase& c : results.cases) {
      if (c.method != method) continue;
      if (c.instance <= 0) {  // the scene's first (or only) row
        ++r.scenes;
        times.push_back(c.time_ms);
        r.detections += c.detections;
        r.wrong_identity += c.wrong_identity;
        r.false_detections += c.false_detections;
      }
      if (c.instance < 0) {
        ++r.negative_scenes;
        r.negative_with_detections += c.detections > 0;
        continue;
      }
      instances.push_back(&c);
      ++r.instances;
      r.found += c.found;
      r.found_iou += c.found_iou;
      if (c.found) errors.push_back(c.corner_error);
      if (c.truth_refound >= 0) {
        ++r.truth_measured;
        r.truth_verifiable += c.truth_verifiable;
        r.truth_verifiable_found += c.truth_verifiable && c.found_iou;
        r.truth_matched += c.truth_enough_matches;
        r.truth_verifiable_matched += c.truth_verifiable && c.truth_enough_matches;
        shown.push_back(c.truth_shown);
        refound.push_back(c.truth_refound);
      }
      const TruthScene& scene = results.manifest.scenes[static_cast<std::size_t>(c.scene)];
      if (scene.instances[static_cast<std::size_t>(c.instance)].has_homography) {
        ++r.homography_instances;
        const double e = c.homography_error;
        r.within2 += e >= 0 && e <= 2;
        r.within5 += e >= 0 && e <= 5;
        r.within10 += e >= 0 && e <= 10;
      }
    }
    r.median_corner_error = errors.empty() ? -1 : percentile(errors, 0.5);
    if (!shown.empty()) {
      r.median_truth_shown = percentile(shown, 0.5);
      r.median_truth_refound = percentile(refound, 0.5);
    }
    r.median_ms = percentile(times, 0.5);
    r.p90_ms = percentile(times, 0.9);
    r.by_size = bin_cases(instances, size_edges(), true);
    r.by_scale = bin_cases(instances, scale_edges(), false);
    rows.push_back(r);
  }
  return rows;
}

std::string truth_text(const std::vector<TruthRow>& rows, const TruthEvalOptions& options,
                       const TruthResults& results) {
  std::string out;
  char line[512];
  const int negatives = rows.empty() ? 0 : rows[0].negative_scenes;
  const int instances = rows.empty() ? 0 : rows[0].instances;
  std::snprintf(line, sizeof(line),
                "%s: %zu scenes, %d instances, %d scenes without any; found: every corner "
                "within %.3g px (order-free), or IoU >= %.2g\n",
                results.manifest.path.c_str(), results.manifest.scenes.size(), instances, negatives,
                options.tolerance, options.min_iou);
  out += line;
  std::snprintf(line, sizeof(line), "%-13s %9s %13s %13s %8s %7s %7s %12s %8s %8s\n", "method",
                "instances", "found", "found(IoU)", "med.err", "wrong", "false", "neg.w/det",
                "med.ms", "p90.ms");
  out += line;
  for (const TruthRow& r : rows) {
    const double n = std::max(r.instances, 1);
    char found[32], found_iou[32], negative[32];
    std::snprintf(found, sizeof(found), "%d (%.0f%%)", r.found, 100.0 * r.found / n);
    std::snprintf(found_iou, sizeof(found_iou), "%d (%.0f%%)", r.found_iou,
                  100.0 * r.found_iou / n);
    std::snprintf(negative, sizeof(negative), "%d/%d", r.negative_with_detections,
                  r.negative_scenes);
    char error[32] = "-";
    if (r.median_corner_error >= 0)
      std::snprintf(error, sizeof(error), "%.2f", r.median_corner_error);
    std::snprintf(line, sizeof(line), "%-13s %9d %13s %13s %8s %7d %7d %12s %8.1f %8.1f\n",
                  r.method.c_str(), r.instances, found, found_iou, error, r.wrong_identity,
                  r.false_detections, negative, r.median_ms, r.p90_ms);
    out += line;
  }
  if (!rows.empty() && rows[0].homography_instances > 0) {
    out += "\nHomography truth: median error of the model grid points inside the scene\n";
    std::snprintf(line, sizeof(line), "%-13s %9s %8s %8s %8s\n", "method", "instances", "<=2px",
                  "<=5px", "<=10px");
    out += line;
    for (const TruthRow& r : rows) {
      std::snprintf(line, sizeof(line), "%-13s %9d %8d %8d %8d\n", r.method.c_str(),
                    r.homography_instances, r.within2, r.within5, r.within10);
      out += line;
    }
  }
  bool any_truth_support = false;
  for (const TruthRow& r : rows) any_truth_support = any_truth_support || r.truth_measured > 0;
  if (any_truth_support) {
    out +=
        "\nAt the ground-truth pose (keygraph): model keypoints shown and re-found among the "
        "frame's\n(medians); instances the keypoints could confirm; instances with enough "
        "correct keygraph\ncorrespondences for a pose; the confirmable ones with them, and "
        "found (IoU)\n";
    std::snprintf(line, sizeof(line), "%-13s %9s %7s %8s %12s %8s %10s %7s\n", "method", "measured",
                  "shown", "refound", "confirmable", "matched", "both", "found");
    out += line;
    for (const TruthRow& r : rows) {
      if (r.truth_measured == 0) continue;
      std::snprintf(line, sizeof(line), "%-13s %9d %7.0f %8.0f %12d %8d %10d %7d\n",
                    r.method.c_str(), r.truth_measured, r.median_truth_shown,
                    r.median_truth_refound, r.truth_verifiable, r.truth_matched,
                    r.truth_verifiable_matched, r.truth_verifiable_found);
      out += line;
    }
  }
  if (instances == 0) return out;
  for (const bool by_size : {true, false}) {
    out += by_size ? "\nFound / instances by the object's long edge in the scene (px)\n"
                   : "\nFound / instances by the object's scale relative to the model image\n";
    const std::vector<TruthBin>& bins = by_size ? rows[0].by_size : rows[0].by_scale;
    std::snprintf(line, sizeof(line), "%-13s", by_size ? "long edge" : "scale");
    out += line;
    for (const TruthBin& b : bins) {
      if (b.instances == 0) continue;
      std::snprintf(line, sizeof(line), " %10s", bin_label(b, by_size).c_str());
      out += line;
    }
    out += "\n";
    for (const TruthRow& r : rows) {
      std::snprintf(line, sizeof(line), "%-13s", r.method.c_str());
      out += line;
      for (const TruthBin& b : by_size ? r.by_size : r.by_scale) {
        if (b.instances == 0) continue;
        char cell[32];
        std::snprintf(cell, sizeof(cell), "%d/%d", b.found, b.instances);
        std::snprintf(line, sizeof(line), " %10s", cell);
        out += line;
      }
      out += "\n";
    }
  }
  for (const TruthRow& r : rows) {
    if (r.truth_measured == 0) continue;
    std::snprintf(line, sizeof(line),
                  "\nAt the ground-truth pose by long edge (%s): instances measured, confirmable "
                  "by the\nkeypoints, with >= 1 and with enough correct correspondences, found "
                  "(IoU); each miss\nby its first cause: too few keypoints re-found, too few "
                  "correct correspondences, pose\n%-10s %8s %11s %9s %7s %6s %10s %16s %5s\n",
                  r.method.c_str(), "long edge", "measured", "confirmable", ">=1 corr", "enough",
                  "found", "keypoints", "correspondences", "pose");
    out += line;
    for (const TruthBin& b : r.by_size) {
      if (b.measured == 0) continue;
      std::snprintf(line, sizeof(line), "%-10s %8d %11d %9d %7d %6d %10d %16d %5d\n",
                    bin_label(b, true).c_str(), b.measured, b.confirmable, b.some_matches,
                    b.enough_matches, b.found_iou, b.missed_keypoints, b.missed_correspondences,
                    b.missed_pose);
      out += line;
    }
  }
  return out;
}

std::string truth_gallery_path(const std::string& dir, const std::string& method, int scene,
                               const TruthResults& results) {
  char prefix[16];
  std::snprintf(prefix, sizeof(prefix), "%04d_", scene);
  return (std::filesystem::path(dir) / "gallery" / method /
          (prefix +
           std::filesystem::path(results.manifest.scenes[static_cast<std::size_t>(scene)].scene)
               .stem()
               .string() +
           ".png"))
      .string();
}

namespace {

const char* const kTruthFiles[] = {"truth-cases.csv", "truth-detections.csv", "truth-summary.json",
                                   "truth-by-size.png"};

// Earlier runs' gallery pictures in `dir`/gallery that this run does not
// write, and the directories they leave empty: METHOD/NNNN_*.png files
// (links included, never followed), directories last. `written` sorted.
std::vector<std::string> stale_gallery(const std::string& dir,
                                       const std::vector<std::string>& written) {
  namespace fs = std::filesystem;
  std::vector<std::string> files, dirs;
  std::error_code ec;
  const fs::path gallery = fs::path(dir) / "gallery";
  if (!fs::is_directory(fs::symlink_status(gallery, ec))) return {};
  for (const fs::directory_entry& m : fs::directory_iterator(gallery, ec)) {
    if (!fs::is_directory(m.symlink_status(ec))) continue;
    for (const fs::directory_entry& f : fs::directory_iterator(m.path(), ec)) {
      const std::string name = f.path().filename().string();
      // NNNN_STEM.png: four or more digits, an underscore.
      const std::size_t digits = name.find_first_not_of("0123456789");
      const bool ours = digits != std::string::npos && digits >= 4 && name[digits] == '_' &&
                        name.size() > 4 && name.compare(name.size() - 4, 4, ".png") == 0;
      if (ours && !std::binary_search(written.begin(), written.end(), f.path().string()))
        files.push_back(f.path().string());
    }
    dirs.push_back(m.path().string());
  }
  dirs.push_back(gallery.string());
  files.insert(files.end(), dirs.begin(), dirs.end());
  return files;
}

}  // namespace

Status check_truth_report(const std::string& dir, const TruthEvalOptions& options,
                          const TruthResults& results) {
  if (Status s = platform::check_output_directory(dir); !s) return s;
  platform::OutputSet out(dir, results.inputs);
  for (const char* name : kTruthFiles) {
    if (Status s = out.check(dir + "/" + name); !s) return s;
  }
  if (options.gallery) {
    // Any scene may be drawn for any method.
    for (const std::string& method : results.methods) {
      for (std::size_t si = 0; si < results.manifest.scenes.size(); ++si) {
        if (Status s = out.check(truth_gallery_path(dir, method, static_cast<int>(si), results));
            !s)
          return s;
      }
    }
  }
  return Status::ok();
}

Status write_truth_report(const std::string& dir, const TruthEvalOptions& options,
                          const TruthResults& results) {
  platform::OutputSet out(dir, results.inputs);
  const std::vector<TruthScene>& scenes = results.manifest.scenes;
  std::ostringstream cases;
  cases << "method,scene,line,scene_file,instance,models,found,found_iou,corner_error,iou,"
           "long_edge,scale,homography_error,detections,wrong_identity,false_detections,time_ms,"
           "truth_shown,truth_refound,truth_z,truth_verifiable,truth_matches\n";
  for (const TruthCase& c : results.cases) {
    const TruthScene& scene = scenes[static_cast<std::size_t>(c.scene)];
    cases << csv_field(c.method) << ',' << c.scene << ',' << scene.line << ','
          << csv_field(scene.scene) << ',' << c.instance << ','
          << csv_field(model_list(scene, c.instance)) << ',' << c.found << ',' << c.found_iou << ','
          << c.corner_error << ',' << c.iou << ',' << c.long_edge << ',' << c.scale << ','
          << c.homography_error << ',' << c.detections << ',' << c.wrong_identity << ','
          << c.false_detections << ',' << c.time_ms << ',' << c.truth_shown << ','
          << c.truth_refound << ',' << c.truth_z << ',' << c.truth_verifiable << ','
          << c.truth_matches << '\n';
  }
  Status s = out.add(dir + "/truth-cases.csv", cases.str());
  if (!s) return s;
  std::ostringstream detections;
  detections << "method,scene,line,scene_file,model,kind,instance,x1,y1,x2,y2,x3,y3,x4,y4\n";
  for (const TruthDetection& d : results.detections) {
    const TruthScene& scene = scenes[static_cast<std::size_t>(d.scene)];
    detections << csv_field(d.method) << ',' << d.scene << ',' << scene.line << ','
               << csv_field(scene.scene) << ','
               << csv_field(results.models[static_cast<std::size_t>(d.model)].name) << ','
               << detection_kind_name(d.kind) << ',' << d.instance;
    for (const Point2f& p : d.corners) detections << ',' << p.x << ',' << p.y;
    detections << '\n';
  }
  if (s = out.add(dir + "/truth-detections.csv", detections.str()); !s) return s;

  const std::vector<TruthRow> rows = truth_tallies(results);
  std::ostringstream j;
  j << "{\n  \"protocol\": \"truth\",\n  \"manifest\": " << json_quote(results.manifest.path)
    << ",\n  \"models\": " << json_quote(options.models.empty() ? options.index : options.models)
    << ",\n  \"tolerance_px\": " << json_value(options.tolerance)
    << ",\n  \"min_iou\": " << json_value(options.min_iou) << ",\n  \"scenes\": " << scenes.size()
    << ",\n  \"results\": [\n";
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const TruthRow& r = rows[i];
    j << "    {\"method\": " << json_quote(r.method) << ", \"scenes\": " << r.scenes
      << ", \"instances\": " << r.instances << ", \"found\": " << r.found
      << ", \"found_iou\": " << r.found_iou << ", \"median_corner_error_px\": "
      << json_value(r.median_corner_error >= 0 ? r.median_corner_error : NAN)
      << ", \"wrong_identity\": " << r.wrong_identity
      << ", \"false_detections\": " << r.false_detections
      << ", \"scenes_without_instances\": " << r.negative_scenes
      << ", \"scenes_without_instances_with_detections\": " << r.negative_with_detections
      << ", \"homography_instances\": " << r.homography_instances
      << ", \"homography_within_2px\": " << r.within2
      << ", \"homography_within_5px\": " << r.within5
      << ", \"homography_within_10px\": " << r.within10
      << ", \"truth_measured\": " << r.truth_measured
      << ", \"truth_verifiable\": " << r.truth_verifiable
      << ", \"truth_verifiable_found\": " << r.truth_verifiable_found
      << ", \"truth_matched\": " << r.truth_matched
      << ", \"truth_verifiable_matched\": " << r.truth_verifiable_matched
      << ", \"median_truth_shown\": "
      << json_value(r.median_truth_shown >= 0 ? r.median_truth_shown : NAN)
      << ", \"median_truth_refound\": "
      << json_value(r.median_truth_refound >= 0 ? r.median_truth_refound : NAN)
      << ", \"median_ms\": " << json_value(r.median_ms) << ", \"p90_ms\": " << json_value(r.p90_ms)
      << ",\n     \"by_long_edge_px\": " << bins_json(r.by_size)
      << ",\n     \"by_scale\": " << bins_json(r.by_scale) << "}"
      << (i + 1 < rows.size() ? ",\n" : "\n");
  }
  j << "  ]\n}\n";
  if (s = out.add(dir + "/truth-summary.json", j.str()); !s) return s;
  if (s = add_png(out, dir + "/truth-by-size.png", truth_size_plot(rows)); !s) return s;
  // The gallery, one picture in memory at a time, drawn from the scene file.
  std::vector<std::string> gallery;
  for (const TruthGalleryEntry& g : results.gallery) {
    const std::string path = truth_gallery_path(dir, g.method, g.scene, results);
    cv::Mat gray;
    if (s = load_gray(scenes[static_cast<std::size_t>(g.scene)].path, gray); !s) return s;
    std::vector<FoundQuad> found;
    std::vector<DetectionKind> kinds;
    for (const TruthDetection& d : results.detections) {
      if (d.method != g.method || d.scene != g.scene) continue;
      FoundQuad f;
      f.model = d.model;
      std::copy(d.corners, d.corners + 4, f.corners);
      found.push_back(f);
      kinds.push_back(d.kind);
    }
    const cv::Mat picture =
        draw_truth_scene(gray, truth_quads(results, g.scene), found, kinds, results.models);
    if (s = add_png(out, path, picture); !s) return s;
    gallery.push_back(path);
  }
  // What an earlier run drew and this one does not is no longer this report's.
  std::sort(gallery.begin(), gallery.end());
  for (const std::string& stale : stale_gallery(dir, gallery)) out.remove_at_commit(stale);
  return out.commit();
}

}  // namespace kg
