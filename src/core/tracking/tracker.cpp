// The Tracker (keygraph/tracker.h): constant-velocity prediction of each
// object's corners, confirmation by aligning the model's appearance from the
// prediction (core/pose/appearance_align.h), detection when needed.
#include "keygraph/tracker.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>
#include <vector>

#include "core/image/blur.h"
#include "core/image/plane.h"
#include "core/pose/appearance_align.h"
#include "core/pose/homography.h"
#include "core/pose/overlap.h"
#include "core/support/workspace.h"
#include "core/tracking/motion_blur.h"

namespace kg {

namespace {

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t).count();
}

Status check_options(const TrackerOptions& o) {
  if (o.detect_interval < 1)
    return {StatusCode::kInvalidArgument, "tracker: detect_interval must be >= 1"};
  if (!(o.min_correlation > 0.0 && o.min_correlation < 1.0))
    return {StatusCode::kInvalidArgument, "tracker: min_correlation must be in (0, 1)"};
  if (o.max_tracks < 1 || o.max_tracks > kMaxDetections)
    return {StatusCode::kInvalidArgument,
            "tracker: max_tracks must be in 1.." + std::to_string(kMaxDetections)};
  if (!(o.smoothing >= 0.0 && o.smoothing < 1.0))
    return {StatusCode::kInvalidArgument, "tracker: smoothing must be in [0, 1)"};
  return Status::ok();
}

}  // namespace

struct Tracker::State {
  State(Detector& d, const TrackerOptions& o)
      : detector(&d),
        options(o),
        blurred(std::pmr::new_delete_resource()),
        blur_scratch(std::pmr::new_delete_resource()),
        aligner(std::pmr::new_delete_resource()) {}

  struct Track {
    int id = -1;
    Detection detection;  // as last reported
    Point2f corners[4];   // measured this frame (or at the last detection)
    Point2f previous[4];  // measured the frame before
    bool has_previous = false;
    bool seen = false;  // confirmed or detected this frame
  };

  // The blurred part of the frame the alignments see: `view` is frame
  // pixels [x, x + width) x [y, y + height).
  struct Region {
    ImageView view;
    int x = 0, y = 0;
  };
  // Track t's corners in this frame moving at `velocity` times the corners'
  // last step (1: constant velocity; 0: where they were).
  static void predict(const Track& t, float velocity, Point2f (&predicted)[4]);
  // Aligns track t's appearance from `predicted` (frame pixels) into `h`;
  // its correlation when measured and plausible, else -1.
  // `pixels`: the appearance to align (nullptr: the stored one).
  double align_from(const Track& t, const Point2f (&predicted)[4], const Region& region,
                    const std::uint8_t* pixels, Homography& h);
  // Smears t's stored appearance into `smeared` along `step` (the mean
  // corner step in frame pixels over one frame) over the exposure; false
  // when the step is too small to blur.
  bool smear(const Track& t, Point2f step);
  // Blurs the part of `frame` around every track's prediction (the
  // alignments never look further; the rest of the frame is not blurred).
  Region blur_around_tracks(ImageView frame);
  // Predicts track t's pose in this frame and aligns its model's appearance
  // from there; false when the object is lost.
  bool confirm(Track& t, const Region& region);
  // The reported corners of `t` after `measured` was measured.
  void report(Track& t, const Point2f* measured, bool smooth);

  Detector* detector;
  TrackerOptions options;
  Status status;
  TrackerStats stats;
  bool can_track = false;
  int max_width = 0, max_height = 0;
  Plane<std::uint8_t> blurred;
  Plane<float> blur_scratch;
  AppearanceAligner aligner;
  std::vector<std::uint8_t> smeared;  // an appearance smeared by motion (reserved)
  // Exposure as a share of the frame interval, for the smear; steps (px
  // per frame) below kMinSmearStep are not smeared.
  static constexpr float kExposure = 0.5f;
  static constexpr float kMinSmearStep = 6.f;
  // A measured step this far from the one smeared for is smeared again.
  static constexpr float kResmearDifference = 3.f;
  DetectionList found;
  Track tracks[kMaxDetections];
  int track_count = 0;
  int next_id = 0;
  // Tracks lost lately, remembered (never reported) so that the object
  // keeps its id when detection finds it again near where it was lost: a
  // tracker that loses an object for a few frames of fast motion has not
  // met a new one.
  struct Lost {
    int id = -1;
    int model_id = -1;
    Point2f corners[4];
    long long frame = 0;  // stats.frames when it was lost
  };
  static constexpr long long kRecallFrames = 30;
  Lost lost[kMaxDetections];
  int lost_count = 0;
  void remember(const Track& t);
  // The id of a lost track of d's model near d (and forgets it), or -1.
  int recall(const Detection& d);
};

void Tracker::State::remember(const Track& t) {
  int at = lost_count < kMaxDetections ? lost_count++ : 0;
  if (at == 0 && lost_count == kMaxDetections) {  // full: replace the oldest
    for (int i = 1; i < lost_count; ++i)
      if (lost[i].frame < lost[at].frame) at = i;
  }
  lost[at].id = t.id;
  lost[at].model_id = t.detection.model_id;
  std::copy_n(t.corners, 4, lost[at].corners);
  lost[at].frame = stats.frames;
}

int Tracker::State::recall(const Detection& d) {
  // The nearest lost track of d's model, its centre within 4 times its
  // size of d's (a fast pan may lose an object and find it again far from
  // there; two lost objects of one model keep theirs by distance).
  const auto centre_of = [](const Point2f* c) {
    return Point2f{(c[0].x + c[1].x + c[2].x + c[3].x) / 4,
                   (c[0].y + c[1].y + c[2].y + c[3].y) / 4};
  };
  const Point2f centre = centre_of(d.corners);
  int best = -1;
  float best_distance = 0.f;
  for (int i = 0; i < lost_count; ++i) {
    const Lost& l = lost[i];
    if (l.model_id != d.model_id || stats.frames - l.frame > kRecallFrames) continue;
    float size = 0.f;
    for (int c = 0; c < 4; ++c)
      size = std::max(size, std::hypot(l.corners[c].x - l.corners[(c + 2) % 4].x,
                                       l.corners[c].y - l.corners[(c + 2) % 4].y));
    const Point2f at = centre_of(l.corners);
    const float distance = std::hypot(at.x - centre.x, at.y - centre.y);
    if (distance > 4.f * size || (best >= 0 && distance >= best_distance)) continue;
    best = i;
    best_distance = distance;
  }
  if (best < 0) return -1;
  const int id = lost[best].id;
  lost[best] = lost[--lost_count];
  return id;
}

void Tracker::State::predict(const Track& t, float velocity, Point2f (&predicted)[4]) {
  for (int c = 0; c < 4; ++c) {
    const Point2f now = t.corners[c];
    const Point2f step = t.has_previous ? Point2f{now.x - t.previous[c].x, now.y - t.previous[c].y}
                                        : Point2f{0.f, 0.f};
    predicted[c] = {now.x + velocity * step.x, now.y + velocity * step.y};
  }
}

double Tracker::State::align_from(const Track& t, const Point2f (&predicted)[4],
                                  const Region& region, const std::uint8_t* pixels, Homography& h) {
  const ModelIndex& index = detector->index();
  const ModelInfo info = index.model(t.detection.model_id);
  const ModelAppearance stored = index.appearance(t.detection.model_id);
  if (stored.empty()) return -1.0;
  // The homography through the predicted corners, in the blurred region's
  // pixels for the alignment, then back in the frame's.
  if (!fit_homography(info.outline, predicted, 4, h)) return -1.0;
  const auto shift = [&h](double dx, double dy) {
    for (int i = 0; i < 3; ++i) {
      h[static_cast<std::size_t>(i)] += dx * h[static_cast<std::size_t>(6 + i)];
      h[static_cast<std::size_t>(3 + i)] += dy * h[static_cast<std::size_t>(6 + i)];
    }
  };
  shift(-region.x, -region.y);
  const AppearanceFit fit = aligner.align({pixels != nullptr ? pixels : stored.pixels, stored.width,
                                           stored.height, stored.scale, stored.scale},
                                          region.view, h);
  shift(region.x, region.y);
  if (!fit.measured) return -1.0;
  const double ncc = fit.aligned ? fit.ncc : fit.ncc_before;
  const RansacParams& rp = detector->options().ransac;
  if (!is_plausible_pose(h, info.width, info.height, rp,
                         smallest_area_scale(index.params(), info.width, info.height)))
    return -1.0;
  return ncc;
}

bool Tracker::State::smear(const Track& t, Point2f step) {
  if (std::hypot(step.x, step.y) < kMinSmearStep) return false;
  const ModelIndex& index = detector->index();
  const ModelInfo info = index.model(t.detection.model_id);
  const ModelAppearance stored = index.appearance(t.detection.model_id);
  if (stored.empty()) return false;
  Point2f centre{0.f, 0.f};
  for (const Point2f& c : t.corners) centre = {centre.x + c.x / 4, centre.y + c.y / 4};
  // The streak over the exposure, from frame pixels into appearance pixels
  // through the object's last pose.
  Homography to_model;
  if (!fit_homography(t.corners, info.outline, 4, to_model)) return false;
  const float e = 0.5f * kExposure;
  const Point2f a = kg::apply(to_model, {centre.x - e * step.x, centre.y - e * step.y});
  const Point2f b = kg::apply(to_model, {centre.x + e * step.x, centre.y + e * step.y});
  const float dx = (b.x - a.x) * stored.scale, dy = (b.y - a.y) * stored.scale;
  if (!(std::hypot(dx, dy) >= 1.f) || !std::isfinite(dx) || !std::isfinite(dy)) return false;
  const std::size_t n = static_cast<std::size_t>(stored.width) * stored.height;
  if (n > smeared.capacity()) return false;
  smeared.resize(n);
  blur_along(stored.pixels, stored.width, stored.height, dx, dy, smeared.data());
  return true;
}

namespace {

// The mean step from `from` to `to`, corner by corner.
Point2f mean_step(const Point2f* from, const Point2f* to) {
  Point2f step{0.f, 0.f};
  for (int c = 0; c < 4; ++c)
    step = {step.x + (to[c].x - from[c].x) / 4, step.y + (to[c].y - from[c].y) / 4};
  return step;
}

}  // namespace

bool Tracker::State::confirm(Track& t, const Region& region) {
  const ModelInfo info = detector->index().model(t.detection.model_id);
  // From the constant-velocity prediction, with the appearance smeared as
  // that motion blurs the object when it is fast; where the motion turned
  // or stopped (a hand's pan ends), from where the object was.
  Point2f predicted[4];
  predict(t, 1.f, predicted);
  const Point2f predicted_step = mean_step(t.corners, predicted);
  Homography h;
  const bool smeared_first = smear(t, predicted_step);
  double ncc = align_from(t, predicted, region, smeared_first ? smeared.data() : nullptr, h);
  if (!(ncc >= options.min_correlation) && smeared_first)
    ncc = align_from(t, predicted, region, nullptr, h);
  if (!(ncc >= options.min_correlation) && t.has_previous) {
    predict(t, 0.f, predicted);
    ncc = align_from(t, predicted, region, nullptr, h);
  }
  if (!(ncc >= options.min_correlation)) return false;
  // The motion this frame as measured, when fast and not what the smear
  // assumed (a pan starting or turning): smeared by it, aligned again from
  // there, kept when it correlates better.
  Point2f aligned[4];
  for (int c = 0; c < 4; ++c) aligned[c] = kg::apply(h, info.outline[c]);
  const Point2f step = mean_step(t.corners, aligned);
  const Point2f assumed = smeared_first ? predicted_step : Point2f{0.f, 0.f};
  if (std::hypot(step.x - assumed.x, step.y - assumed.y) >= kResmearDifference && smear(t, step)) {
    Homography again;
    const double ncc_again = align_from(t, aligned, region, smeared.data(), again);
    if (ncc_again > ncc) {
      h = again;
      ncc = ncc_again;
    }
  }
  Point2f measured[4];
  for (int c = 0; c < 4; ++c) measured[c] = kg::apply(h, info.outline[c]);
  std::copy_n(t.corners, 4, t.previous);
  t.has_previous = true;
  std::copy_n(measured, 4, t.corners);
  t.detection.homography = h;
  t.detection.appearance = ncc;
  t.detection.tracked = true;
  report(t, measured, true);
  return true;
}

Tracker::State::Region Tracker::State::blur_around_tracks(ImageView frame) {
  // The predicted outlines' bounding box with a margin for the alignment's
  // steps (it starts from the prediction and moves a few pixels; a
  // prediction further off than the margin is lost anyway).
  float x0 = 1e30f, y0 = 1e30f, x1 = -1e30f, y1 = -1e30f;
  for (int i = 0; i < track_count; ++i) {
    for (const float velocity : {1.f, 0.f}) {  // both starts of confirm()
      Point2f predicted[4];
      predict(tracks[i], velocity, predicted);
      for (const Point2f& p : predicted) {
        x0 = std::min(x0, p.x);
        y0 = std::min(y0, p.y);
        x1 = std::max(x1, p.x);
        y1 = std::max(y1, p.y);
      }
    }
  }
  constexpr float kMargin = 48.f;
  const auto clamp_to = [](float v, int hi) {
    return static_cast<int>(std::clamp(v, 0.f, static_cast<float>(hi)));
  };
  Region r;
  r.x = clamp_to(std::floor(x0 - kMargin), frame.width);
  r.y = clamp_to(std::floor(y0 - kMargin), frame.height);
  const int right = clamp_to(std::ceil(x1 + kMargin) + 1.f, frame.width);
  const int bottom = clamp_to(std::ceil(y1 + kMargin) + 1.f, frame.height);
  if (right - r.x < 2 || bottom - r.y < 2) {  // nothing predicted inside the frame
    r.view = ImageView{};
    return r;
  }
  // Blurred with the kernel's radius around it, so that the region's pixels
  // are those of the whole frame blurred.
  const float sigma = detector->index().params().descriptor.blur_sigma;
  const int pad = sigma > 0.f ? blur_radius(sigma) : 0;
  const int bx = std::max(r.x - pad, 0), by = std::max(r.y - pad, 0);
  const int bw = std::min(right + pad, frame.width) - bx;
  const int bh = std::min(bottom + pad, frame.height) - by;
  gaussian_blur(ImageView(frame.row(by) + bx, bw, bh, frame.stride), sigma, blurred, blur_scratch);
  const ImageView all = view_of(blurred);
  r.view = ImageView(all.row(r.y - by) + (r.x - bx), right - r.x, bottom - r.y, all.stride);
  return r;
}

void Tracker::State::report(Track& t, const Point2f* measured, bool smooth) {
  const auto a = static_cast<float>(smooth ? options.smoothing : 0.0);
  for (int c = 0; c < 4; ++c) {
    const Point2f before = t.detection.corners[c];
    t.detection.corners[c] = {a * before.x + (1.f - a) * measured[c].x,
                              a * before.y + (1.f - a) * measured[c].y};
  }
}

Tracker::Tracker(Detector& detector, const TrackerOptions& options)
    : state_(new State(detector, options)) {
  State& s = *state_;
  s.status = check_options(options);
  if (s.status) s.status = detector.status();
  if (!s.status) return;
  const ModelIndex& index = detector.index();
  s.can_track = index.has_appearance();
  if (!s.can_track)
    s.status = {StatusCode::kInvalidArgument,
                "tracker: the index stores no model appearances (format 6.2 and later, "
                "views.appearance_size > 0): every frame is detected"};
  s.max_width = detector.limits().max_width;
  s.max_height = detector.limits().max_height;
  if (!s.can_track) return;
  const float sigma = index.params().descriptor.blur_sigma;
  s.blurred.reserve(s.max_width, s.max_height);
  s.blur_scratch.reserve(s.max_width + 2 * blur_radius(sigma), 2);
  s.aligner.reserve(index.max_appearance_pixels());
  s.smeared.reserve(static_cast<std::size_t>(index.max_appearance_pixels()));
}

Tracker::~Tracker() {
  delete state_;
}

const Status& Tracker::status() const {
  return state_->status;
}
const TrackerStats& Tracker::stats() const {
  return state_->stats;
}
const TrackerOptions& Tracker::options() const {
  return state_->options;
}

void Tracker::reset() {
  state_->track_count = 0;
  state_->lost_count = 0;
  state_->stats = TrackerStats{};
}

Status Tracker::process(ImageView frame, DetectionList& out) {
  State& s = *state_;
  out.clear();
  TrackerStats& st = s.stats;
  st.confirmed = st.lost = 0;
  st.detected = false;
  st.ms_track = st.ms_detect = 0.0;
  if (!s.detector->status()) return s.detector->status();
  if (!check_options(s.options)) return check_options(s.options);
  if (frame.width > s.max_width || frame.height > s.max_height)
    return {StatusCode::kInvalidArgument,
            "tracker: frame " + std::to_string(frame.width) + "x" + std::to_string(frame.height) +
                " is larger than the detector's limits when the tracker was made (" +
                std::to_string(s.max_width) + "x" + std::to_string(s.max_height) + ")"};
  ++st.frames;
  for (int i = 0; i < s.track_count; ++i) s.tracks[i].seen = false;

  // Confirm each track around its prediction; drop the lost ones in place.
  if (s.can_track && s.track_count > 0 && !frame.empty()) {
    const auto start = Clock::now();
    const State::Region region = s.blur_around_tracks(frame);
    int kept = 0;
    for (int i = 0; i < s.track_count; ++i) {
      State::Track& t = s.tracks[i];
      if (s.confirm(t, region)) {
        t.seen = true;
        ++st.confirmed;
        s.tracks[kept++] = t;
      } else {
        ++st.lost;
        s.remember(t);
      }
    }
    s.track_count = kept;
    st.ms_track = ms_since(start);
  }

  // Detect when nothing is followed, when an object was lost, and every
  // detect_interval frames.
  const bool detect = !s.can_track || s.track_count == 0 || st.lost > 0 ||
                      st.frames % s.options.detect_interval == 0;
  DetectionList& extra = s.found;  // detections beyond max_tracks, reported untracked
  int extras = 0;
  if (detect) {
    const auto start = Clock::now();
    DetectionList found;  // fixed capacity: no heap
    if (Status d = s.detector->detect(frame, found); !d) return d;
    st.detected = true;
    ++st.detected_frames;
    extra.clear();
    for (Detection d : found) {
      d.tracked = false;
      // The track this detection continues: the same model, overlapping.
      int match = -1;
      for (int i = 0; i < s.track_count && match < 0; ++i) {
        const State::Track& t = s.tracks[i];
        if (t.detection.model_id == d.model_id && outlines_overlap(t.corners, d.corners) &&
            !(t.seen && !t.detection.tracked))
          match = i;
      }
      if (match < 0 && s.can_track && s.track_count < s.options.max_tracks) {
        State::Track& t = s.tracks[s.track_count++];
        t = State::Track{};
        t.id = s.recall(d);
        if (t.id < 0) {
          t.id = s.next_id++;
          if (s.next_id < 0) s.next_id = 0;
        }
        match = s.track_count - 1;
        t.detection = d;
        std::copy_n(d.corners, 4, t.corners);
      } else if (match < 0) {
        d.track_id = -1;
        extra.push_back(d);
        ++extras;
        continue;
      } else {
        State::Track& t = s.tracks[match];
        // A track confirmed this frame keeps the corners of the frame
        // before as its previous ones; otherwise this frame's become them.
        if (!t.seen) {
          std::copy_n(t.corners, 4, t.previous);
          t.has_previous = true;
        }
        std::copy_n(d.corners, 4, t.corners);
        const Detection before = t.detection;
        t.detection = d;
        std::copy_n(before.corners, 4, t.detection.corners);
        s.report(t, d.corners, t.seen);
      }
      State::Track& t = s.tracks[match];
      t.seen = true;
      t.detection.track_id = t.id;
      t.detection.tracked = false;
    }
    st.ms_detect = ms_since(start);
  }
  for (int i = 0; i < s.track_count; ++i) {
    s.tracks[i].detection.track_id = s.tracks[i].id;
    out.push_back(s.tracks[i].detection);
  }
  for (int i = 0; i < extras; ++i) out.push_back(extra[static_cast<std::size_t>(i)]);
  st.tracks = s.track_count;
  return Status::ok();
}

}  // namespace kg
