#include "eval/video_eval.h"

#include <sys/stat.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <set>
#include <sstream>

#include <opencv2/core.hpp>

#include "builder/desktop_detect.h"
#include "builder/image_io.h"
#include "builder/in_memory_index.h"
#include "builder/model_set.h"
#include "eval/quad_geometry.h"
#include "eval/report_io.h"
#include "eval/truth_eval.h"
#include "eval/video_manifest.h"
#include "keygraph/model_index.h"
#include "platform/files/regular_file.h"

namespace kg {

namespace {

using Clock = std::chrono::steady_clock;

// The pairing of a detection's corners with the truth's (of the 8 corner
// orders, the one with the smallest largest distance): the error vector
// of each truth corner.
void corner_errors(const Point2f (&truth)[4], const Point2f (&found)[4], Point2f (&error)[4]) {
  double best = -1;
  for (int dir = 0; dir < 2; ++dir) {
    for (int shift = 0; shift < 4; ++shift) {
      Point2f e[4];
      double worst = 0;
      for (int c = 0; c < 4; ++c) {
        const int f = dir == 0 ? (c + shift) % 4 : (shift - c + 4) % 4;
        e[c] = {found[f].x - truth[c].x, found[f].y - truth[c].y};
        worst = std::max(worst, std::hypot(double{e[c].x}, double{e[c].y}));
      }
      if (best < 0 || worst < best) {
        best = worst;
        std::copy(e, e + 4, error);
      }
    }
  }
}

// What one mode keeps from frame to frame while scoring.
struct ModeState {
  VideoScores scores;
  std::vector<double> errors;  // of found instances
  double jitter_sum = 0;       // of squared corner error changes
  // Per object (its first acceptable model): the last found frame, its
  // corner errors and track id; whether it was absent since; the frames a
  // lost object is still reported.
  struct Object {
    int last_found = -1000;
    Point2f error[4];
    int track = -1;
    bool absent_since = false;
    bool present_before = false;
    int dropping = -1;  // counting frames reported after it left; -1: not
  };
  std::vector<Object> objects;  // by model
  std::set<int> ids;
  double ms_tracked = 0, ms_detected = 0;
};

VideoScores::Part& part_named(VideoScores& s, const std::string& name) {
  for (VideoScores::Part& p : s.parts) {
    if (p.name == name) return p;
  }
  s.parts.push_back({name, 0, 0, 0});
  return s.parts.back();
}

void score_frame(ModeState& m, int frame, const std::vector<TruthQuad>& truth,
                 const DetectionList& list, bool scored, const std::string& part_name,
                 const std::vector<TruthModel>& models, int width, int height,
                 const VideoEvalOptions& options, double tolerance) {
  // Dropping: counted on every frame until the lost object is not reported.
  for (std::size_t model = 0; model < m.objects.size(); ++model) {
    ModeState::Object& o = m.objects[model];
    if (o.dropping < 0) continue;
    bool reported = false;
    for (const Detection& d : list) reported = reported || d.model_id == static_cast<int>(model);
    if (reported) {
      ++o.dropping;
    } else {
      m.scores.drop_frames_max = std::max(m.scores.drop_frames_max, o.dropping);
      m.scores.drop_frames_mean += o.dropping;
      ++m.scores.drop_events;
      o.dropping = -1;
    }
  }
  if (!scored) return;
  ++m.scores.scored_frames;
  std::vector<FoundQuad> found;
  for (const Detection& d : list) {
    FoundQuad f;
    f.model = d.model_id;
    f.homography = d.homography;
    std::copy(d.corners, d.corners + 4, f.corners);
    found.push_back(f);
  }
  std::vector<TruthCase> cases;
  std::vector<DetectionKind> kinds;
  std::vector<int> instance_of;
  score_truth_scene(found, truth, models, width, height, tolerance, options.min_iou, cases, kinds,
                    instance_of);
  for (const DetectionKind k : kinds) m.scores.wrong += k != DetectionKind::kTrue;
  // Objects absent from this frame: a lost one starts its count of frames
  // still reported.
  std::vector<bool> present(models.size(), false);
  for (const TruthQuad& q : truth) present[static_cast<std::size_t>(q.models.front())] = true;
  for (std::size_t model = 0; model < models.size(); ++model) {
    ModeState::Object& o = m.objects[model];
    if (present[model]) {
      o.present_before = true;
      if (o.dropping >= 0) {  // back before it was dropped: the count ends here
        m.scores.drop_frames_max = std::max(m.scores.drop_frames_max, o.dropping);
        m.scores.drop_frames_mean += o.dropping;
        ++m.scores.drop_events;
        o.dropping = -1;
      }
      continue;
    }
    if (!o.absent_since && o.present_before) {
      o.absent_since = true;
      bool reported = false;
      for (const Detection& d : list) reported = reported || d.model_id == static_cast<int>(model);
      if (reported) {
        o.dropping = 1;
      } else {
        ++m.scores.drop_events;
      }
    }
    o.absent_since = true;
    o.present_before = false;
  }
  for (std::size_t i = 0; i < truth.size(); ++i) {
    ++m.scores.instances;
    VideoScores::Part& part = part_named(m.scores, part_name);
    ++part.instances;
    const TruthCase& c = cases[i];
    if (!c.found) continue;
    ++m.scores.found;
    ++part.found;
    m.scores.found_fine += c.corner_error <= options.fine_tolerance;
    part.found_fine += c.corner_error <= options.fine_tolerance;
    m.errors.push_back(c.corner_error);
    // The detection that found it: the true one on this instance.
    const Detection* d = nullptr;
    for (std::size_t k = 0; k < kinds.size(); ++k) {
      if (kinds[k] == DetectionKind::kTrue && instance_of[k] == static_cast<int>(i)) d = &list[k];
    }
    if (d == nullptr) continue;
    ModeState::Object& o = m.objects[static_cast<std::size_t>(truth[i].models.front())];
    Point2f e[4];
    corner_errors(truth[i].corners, d->corners, e);
    if (frame - o.last_found <= 2) {
      for (int k = 0; k < 4; ++k) {
        const double dx = e[k].x - o.error[k].x, dy = e[k].y - o.error[k].y;
        m.jitter_sum += dx * dx + dy * dy;
      }
      ++m.scores.jitter_pairs;
    }
    if (d->track_id >= 0) {
      m.ids.insert(d->track_id);
      if (o.track >= 0 && o.track != d->track_id && !o.absent_since) ++m.scores.id_switches;
      o.track = d->track_id;
    }
    o.absent_since = false;
    o.last_found = frame;
    std::copy(e, e + 4, o.error);
  }
}

void finish(ModeState& m) {
  VideoScores& s = m.scores;
  if (!m.errors.empty()) {
    std::sort(m.errors.begin(), m.errors.end());
    s.median_error = m.errors[m.errors.size() / 2];
  }
  if (s.jitter_pairs > 0) s.jitter_rms = std::sqrt(m.jitter_sum / (4.0 * s.jitter_pairs));
  for (ModeState::Object& o : m.objects) {
    if (o.dropping < 0) continue;  // still reported at the end
    s.drop_frames_max = std::max(s.drop_frames_max, o.dropping);
    s.drop_frames_mean += o.dropping;
    ++s.drop_events;
  }
  if (s.drop_events > 0) s.drop_frames_mean /= s.drop_events;
  s.track_ids = static_cast<int>(m.ids.size());
  if (s.tracked_frames > 0) s.ms_tracked = m.ms_tracked / s.tracked_frames;
  if (s.detected_frames > 0) s.ms_detected = m.ms_detected / s.detected_frames;
  if (s.frames > 0) s.ms_mean = (m.ms_tracked + m.ms_detected) / s.frames;
}

std::string percent(int n, int of) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.1f %%", of > 0 ? 100.0 * n / of : 0.0);
  return buf;
}

std::string fixed(double v, int digits) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.*f", digits, v);
  return buf;
}

}  // namespace

Status evaluate_video(const VideoEvalOptions& options, VideoResults& results,
                      const ProgressFn& progress) {
  results = VideoResults{};
  results.manifest = options.manifest;
  VideoManifest manifest;
  if (Status s = read_video_manifest(options.manifest, manifest); !s) return s;
  const TruthManifest& truth_manifest = manifest.truth;
  auto at_line = [&](const TruthScene& scene, const std::string& what) {
    return Status{StatusCode::kInvalidArgument,
                  options.manifest + ":" + std::to_string(scene.line) + ": " + what};
  };
  if (options.models.empty() == options.index.empty())
    return {StatusCode::kInvalidArgument, "give one of --models DIR|M.json and --index I.kgi"};
  if (!(options.tolerance >= 0) || !(options.fine_tolerance > 0))
    return {StatusCode::kInvalidArgument, "tolerances must be positive"};

  // The models: an index file, or images built into one.
  TruthResults named;  // the models by name, for truth_quads()
  named.manifest = truth_manifest;
  ModelIndex file_index;
  InMemoryIndex built;
  std::vector<ModelSource> sources;
  if (!options.index.empty()) {
    if (options.params_set)
      return {StatusCode::kInvalidArgument,
              "--set changes how models are built; an --index keeps its own parameters"};
    if (Status s = ModelIndex::open(options.index, file_index); !s) return s;
    for (int i = 0; i < file_index.model_count(); ++i) {
      const ModelInfo info = file_index.model(i);
      named.models.push_back(
          {std::string(info.name), static_cast<int>(info.width), static_cast<int>(info.height)});
    }
  } else {
    if (Status s = read_model_sources(options.models, sources); !s) return s;
    for (const ModelSource& m : sources) named.models.push_back({m.name, 0, 0});
  }
  std::vector<std::string> names;
  for (const TruthModel& m : named.models) names.push_back(m.name);
  for (const TruthScene& scene : truth_manifest.scenes) {
    std::string error;
    if (!check_truth_models(scene, names, error)) return at_line(scene, error);
    struct stat info {};
    if (::stat(scene.path.c_str(), &info) != 0)
      return at_line(scene, "frame " + scene.path + ": no such file");
    if (!S_ISREG(info.st_mode))
      return at_line(scene,
                     "frame " + scene.path + ": is " + platform::file_type_name(info.st_mode));
  }
  if (!sources.empty()) {
    ModelBuildOptions build;
    build.params = options.params;
    std::vector<cv::Mat> grays;
    std::vector<BuiltModel> models;
    if (Status s = build_model_set(sources, build, load_gray, grays, models); !s) return s;
    if (Status s = built.build(models, options.params); !s) return s;
    for (std::size_t i = 0; i < sources.size(); ++i) {
      named.models[i].width = grays[i].cols;
      named.models[i].height = grays[i].rows;
    }
  }
  const ModelIndex& index = options.index.empty() ? built.index() : file_index;

  // The first frame sets the size every detector is made for.
  const int frame_count = static_cast<int>(truth_manifest.scenes.size());
  cv::Mat gray;
  if (Status s = load_gray(truth_manifest.scenes.front().path, gray); !s)
    return at_line(truth_manifest.scenes.front(), s.message());
  results.width = gray.cols;
  results.height = gray.rows;
  const double tolerance =
      options.tolerance > 0 ? options.tolerance : (gray.cols > 960 ? 15.0 : 10.0);
  results.tolerance = tolerance;
  const Limits limits = Limits{}.for_frame(gray.cols, gray.rows);
  DesktopDetector tracked_detector(index, limits, options.detector);
  DesktopDetector alone(index, limits, options.detector);
  // Runtime options (--set) are applied by DesktopDetector: its status is
  // the first detect()'s; run one on the first frame to check them.
  {
    DetectionList probe;
    if (Status s = alone.detect(gray, probe); !s) return s;
  }
  Tracker tracker(tracked_detector.core(), options.tracker);
  if (!tracker.status()) return tracker.status();
  // The tracker's detector needs the runtime options too.
  if (!options.detector.options.empty()) {
    DetectionList probe;
    if (Status s = tracked_detector.detect(gray, probe); !s) return s;
  }

  ModeState modes[2];
  modes[0].scores.mode = "tracking";
  modes[1].scores.mode = "detection alone";
  for (ModeState& m : modes) m.objects.resize(named.models.size());
  for (int f = 0; f < frame_count; ++f) {
    const TruthScene& scene = truth_manifest.scenes[static_cast<std::size_t>(f)];
    if (f > 0) {
      if (Status s = load_gray(scene.path, gray); !s) return at_line(scene, s.message());
    }
    if (gray.cols != results.width || gray.rows != results.height)
      return at_line(scene, "frame " + scene.path + " is " + std::to_string(gray.cols) + "x" +
                                std::to_string(gray.rows) + ", the first was " +
                                std::to_string(results.width) + "x" +
                                std::to_string(results.height) + ": a video has one frame size");
    const bool scored = manifest.annotated[static_cast<std::size_t>(f)];
    results.annotated += scored;
    results.with_object += scored && !scene.instances.empty();
    const std::vector<TruthQuad> truth = truth_quads(named, f);
    DetectionList list;
    // Tracking.
    auto start = Clock::now();
    if (Status s = tracker.process(view_of(gray), list); !s) return at_line(scene, s.message());
    double ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
    ModeState& t = modes[0];
    ++t.scores.frames;
    if (tracker.stats().detected) {
      ++t.scores.detected_frames;
      t.ms_detected += ms;
    } else {
      ++t.scores.tracked_frames;
      t.ms_tracked += ms;
    }
    score_frame(t, f, truth, list, scored, manifest.part[static_cast<std::size_t>(f)], named.models,
                gray.cols, gray.rows, options, tolerance);
    // Detection alone.
    start = Clock::now();
    if (Status s = alone.detect(gray, list); !s) return at_line(scene, s.message());
    ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
    ModeState& d = modes[1];
    ++d.scores.frames;
    ++d.scores.detected_frames;
    d.ms_detected += ms;
    score_frame(d, f, truth, list, scored, manifest.part[static_cast<std::size_t>(f)], named.models,
                gray.cols, gray.rows, options, tolerance);
    if (progress) progress(f + 1, frame_count, {});
  }
  results.frames = frame_count;
  for (ModeState& m : modes) {
    finish(m);
    results.modes.push_back(m.scores);
  }
  return Status::ok();
}

std::string video_text(const VideoResults& r) {
  std::ostringstream out;
  out << r.manifest << ": " << r.frames << " frames of " << r.width << "x" << r.height << ", "
      << r.with_object << " with the object, " << (r.annotated - r.with_object) << " without, "
      << (r.frames - r.annotated) << " not scored\n";
  const VideoScores& t = r.modes[0];
  const VideoScores& d = r.modes[1];
  char row[256];
  const auto line = [&](const char* what, const std::string& a, const std::string& b) {
    std::snprintf(row, sizeof(row), "%-44s %18s %18s\n", what, a.c_str(), b.c_str());
    out << row;
  };
  line("", "tracking", "detection alone");
  const std::string tol = "found (every corner <= " + fixed(r.tolerance, 0) + " px)";
  line(tol.c_str(), percent(t.found, t.instances), percent(d.found, d.instances));
  line("found (<= 5 px)", percent(t.found_fine, t.instances), percent(d.found_fine, d.instances));
  line("median corner error of those found, px", fixed(t.median_error, 2),
       fixed(d.median_error, 2));
  line("corner jitter, RMS px", t.jitter_rms < 0 ? "-" : fixed(t.jitter_rms, 2),
       d.jitter_rms < 0 ? "-" : fixed(d.jitter_rms, 2));
  line("id switches / track ids",
       std::to_string(t.id_switches) + " / " + std::to_string(t.track_ids), "-");
  line("wrong detections per scored frame",
       fixed(t.scored_frames ? static_cast<double>(t.wrong) / t.scored_frames : 0, 3) + " (" +
           std::to_string(t.wrong) + ")",
       fixed(d.scored_frames ? static_cast<double>(d.wrong) / d.scored_frames : 0, 3) + " (" +
           std::to_string(d.wrong) + ")");
  line("frames a lost object is still reported",
       fixed(t.drop_frames_mean, 1) + " max " + std::to_string(t.drop_frames_max) + " (" +
           std::to_string(t.drop_events) + ")",
       fixed(d.drop_frames_mean, 1) + " max " + std::to_string(d.drop_frames_max) + " (" +
           std::to_string(d.drop_events) + ")");
  line("frames tracked / detected",
       std::to_string(t.tracked_frames) + " / " + std::to_string(t.detected_frames),
       std::to_string(d.tracked_frames) + " / " + std::to_string(d.detected_frames));
  line("ms per tracked frame", t.tracked_frames ? fixed(t.ms_tracked, 2) : "-", "-");
  line("ms per detected frame", fixed(t.ms_detected, 2), fixed(d.ms_detected, 2));
  line("ms per frame, mean",
       fixed(t.ms_mean, 2) + " (" + fixed(d.ms_mean > 0 ? t.ms_mean / d.ms_mean : 0, 2) + "x)",
       fixed(d.ms_mean, 2));
  // By part, where the manifest names parts.
  if (t.parts.size() > 1 || (t.parts.size() == 1 && !t.parts[0].name.empty())) {
    out << "found (<= " << fixed(r.tolerance, 0) << " px / <= 5 px) by part\n";
    for (std::size_t i = 0; i < t.parts.size(); ++i) {
      const VideoScores::Part& a = t.parts[i];
      const VideoScores::Part& b = d.parts[i];
      const std::string name = "  " +
                               (a.name.empty() ? std::string("(before the first part)") : a.name) +
                               ", " + std::to_string(a.instances) + " frames";
      line(name.c_str(), percent(a.found, a.instances) + " / " + percent(a.found_fine, a.instances),
           percent(b.found, b.instances) + " / " + percent(b.found_fine, b.instances));
    }
  }
  return out.str();
}

std::string video_json(const VideoResults& r) {
  std::ostringstream out;
  out << "{\"manifest\": " << json_quote(r.manifest) << ", \"frames\": " << r.frames
      << ", \"width\": " << r.width << ", \"height\": " << r.height
      << ", \"scored_frames\": " << r.annotated << ", \"with_object\": " << r.with_object
      << ", \"tolerance\": " << json_value(r.tolerance) << ", \"modes\": [";
  for (std::size_t i = 0; i < r.modes.size(); ++i) {
    const VideoScores& s = r.modes[i];
    out << (i ? ", " : "") << "{\"mode\": " << json_quote(s.mode)
        << ", \"instances\": " << s.instances << ", \"found\": " << s.found
        << ", \"found_fine\": " << s.found_fine
        << ", \"median_error\": " << json_value(s.median_error)
        << ", \"jitter_rms\": " << json_value(s.jitter_rms)
        << ", \"jitter_pairs\": " << s.jitter_pairs << ", \"id_switches\": " << s.id_switches
        << ", \"track_ids\": " << s.track_ids << ", \"wrong\": " << s.wrong
        << ", \"drop_events\": " << s.drop_events
        << ", \"drop_frames_mean\": " << json_value(s.drop_frames_mean)
        << ", \"drop_frames_max\": " << s.drop_frames_max
        << ", \"frames_tracked\": " << s.tracked_frames
        << ", \"frames_detected\": " << s.detected_frames
        << ", \"ms_tracked\": " << json_value(s.ms_tracked)
        << ", \"ms_detected\": " << json_value(s.ms_detected)
        << ", \"ms_mean\": " << json_value(s.ms_mean) << ", \"parts\": [";
    for (std::size_t k = 0; k < s.parts.size(); ++k) {
      const VideoScores::Part& p = s.parts[k];
      out << (k ? ", " : "") << "{\"part\": " << json_quote(p.name)
          << ", \"instances\": " << p.instances << ", \"found\": " << p.found
          << ", \"found_fine\": " << p.found_fine << "}";
    }
    out << "]}";
  }
  out << "]}\n";
  return out.str();
}

}  // namespace kg
