// Following what a Detector found from frame to frame (live video). The
// paper ends its speed experiment with "classic tracking techniques ...
// would certainly improve even further": an object found in one frame is a
// few pixels away in the next, so the tracker predicts each object's pose
// (its corners moving at constant velocity), aligns the model's stored
// appearance (the index carries it, format 6.2) onto the frame from there,
// and keeps the object while the aligned appearance still correlates with
// the frame; a tracked frame costs an alignment per object instead of a
// detection. When the object moves fast (6 px a frame or more) the
// appearance is first smeared along that motion over half the frame
// interval, as the camera's motion blur smears the object, and again by
// the motion the alignment measured; when the prediction fails the
// alignment is tried again from where the object was (a pan that stopped
// or turned). Full detection runs when nothing is tracked, when a track was
// lost, and every `detect_interval` frames to pick up new objects; what it
// finds is matched to the tracks by outline, so an object keeps its id,
// also when it was lost at most 30 frames before and is found again within
// 4 times its size of where it was lost.
//
//   kg::Detector detector(index, kg::Limits{}.for_frame(1280, 720));
//   kg::Tracker tracker(detector);                 // allocates here, once
//   kg::DetectionList found;
//   while (camera.next(frame))
//     tracker.process(frame.image, found);         // never allocates
//   // found[i].track_id: stable while the object is followed;
//   // found[i].tracked: confirmed around the prediction (no detection ran)
//
// The detector must outlive the tracker and keep its limits (a detector
// rebuilt for larger frames needs a new tracker). A Tracker is not
// thread-safe; frames must be given in order. Indexes without appearances
// (format < 6.2, or views.appearance_size 0) cannot be tracked: every frame
// is then detected (status() says so).
#pragma once

#include <cstdint>

#include "keygraph/detection.h"
#include "keygraph/detector.h"
#include "keygraph/image.h"
#include "keygraph/status.h"

namespace kg {

struct TrackerOptions {
  // Full detection every this many frames while objects are tracked, to
  // find new ones (1: every frame, as detection alone but with track ids).
  int detect_interval = 10;
  // A track is kept while the model's appearance, aligned onto the frame
  // from the predicted pose, correlates with the frame at least this much
  // (normalised cross-correlation, in (0, 1)); below, the object is lost at
  // once (and detection runs on that frame).
  double min_correlation = 0.75;
  // Objects followed at once, 1..kMaxDetections; detections beyond are
  // reported untracked (track_id -1).
  int max_tracks = 16;
  // Smoothing of the reported corners, in [0, 1): each frame's corners are
  // smoothing * the previous report + (1 - smoothing) * the measured ones.
  // 0 (the default) reports the measured corners: any smoothing lags
  // behind motion by about smoothing / (1 - smoothing) frames.
  double smoothing = 0.0;
};

struct TrackerStats {
  int tracks = 0;          // objects followed after this frame
  int confirmed = 0;       // tracks confirmed around their prediction
  int lost = 0;            // tracks dropped this frame
  bool detected = false;   // full detection ran on this frame
  double ms_track = 0.0;   // the alignments (and the blur they need)
  double ms_detect = 0.0;  // the detection, when it ran
  long long frames = 0;    // frames processed since construction or reset()
  long long detected_frames = 0;
};

class Tracker {
 public:
  // Reserves everything the tracker uses per frame for the detector's
  // limits and index.
  explicit Tracker(Detector& detector, const TrackerOptions& options = TrackerOptions{});
  ~Tracker();
  Tracker(const Tracker&) = delete;
  Tracker& operator=(const Tracker&) = delete;

  // Ok, or why the tracker cannot track (options out of range, a failed
  // detector, an index without appearances: process() then detects every
  // frame).
  const Status& status() const;

  // The objects in `frame`: clears and fills `out` with one detection per
  // object followed (track_id >= 0, tracked true when confirmed around its
  // prediction, false when detection found it this frame) and detections
  // beyond max_tracks (track_id -1). Allocates nothing.
  Status process(ImageView frame, DetectionList& out);

  // Forgets every track (a new scene, a camera switch).
  void reset();

  const TrackerStats& stats() const;
  const TrackerOptions& options() const;

 private:
  struct State;
  State* state_ = nullptr;
};

}  // namespace kg
