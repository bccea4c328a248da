// `keygraph eval --video`: a video with ground truth per frame
// (eval/video_manifest.h) processed as a camera delivers it, once with the
// tracker (kg::Tracker over the detector) and once by detection alone on
// every frame, in the same run and on the same decoded frames (the two
// alternate frame by frame, so that the machine's load touches both alike).
//
// Scores per mode over the frames with ground truth: the instances found
// (every corner within the tolerance, and within the fine tolerance; the
// best of the 8 corner orders), the corner jitter (RMS over pairs of scored
// frames at most 2 apart, both found, of the change of each corner's error
// vector), id switches (a found object reported under another track id than
// when it was last found, without a frame between where it was absent),
// wrong detections (those lying on no instance of their model: neither
// within the tolerance nor at IoU >= 0.5), the frames a lost object is
// still reported (from the first scored frame where it is absent), and the
// time per frame, split into tracked frames and frames where detection ran.
#pragma once

#include <string>
#include <vector>

#include "builder/detector_settings.h"
#include "builder/progress.h"
#include "keygraph/params.h"
#include "keygraph/status.h"
#include "keygraph/tracker.h"

namespace kg {

struct VideoEvalOptions {
  std::string manifest;
  std::string models;  // a directory of model images or a models.json
  std::string index;   // or a built .kgi
  // Every corner within this many pixels; 0: 10 px for frames up to 960
  // pixels wide, 15 px above (the 640x480 and 1280x720 rules).
  double tolerance = 0;
  double fine_tolerance = 5;
  double min_iou = 0.5;
  Params params;            // for building the models (with `models`)
  bool params_set = false;  // --set of a build parameter (not with an index)
  DetectorSettings detector;
  TrackerOptions tracker;
};

// One mode's scores over a sequence.
struct VideoScores {
  std::string mode;          // "tracking" or "detection alone"
  int instances = 0;         // scored instances (frames with the object)
  int found = 0;             // within the tolerance
  int found_fine = 0;        // within the fine tolerance
  double median_error = -1;  // px, over found instances
  double jitter_rms = -1;    // px; -1: no pair of found frames
  int jitter_pairs = 0;
  int id_switches = 0;
  int track_ids = 0;  // distinct track ids given to true detections
  int scored_frames = 0;
  int wrong = 0;                // wrong detections over the scored frames
  int drop_events = 0;          // an object found, then absent
  double drop_frames_mean = 0;  // frames it was still reported after
  int drop_frames_max = 0;
  int frames = 0, tracked_frames = 0, detected_frames = 0;
  double ms_tracked = 0, ms_detected = 0, ms_mean = 0;  // means per frame
  // The instances found in each part of the video ("# part:" lines of the
  // manifest), in the order they first appear.
  struct Part {
    std::string name;
    int instances = 0, found = 0, found_fine = 0;
  };
  std::vector<Part> parts;
};

struct VideoResults {
  std::string manifest;
  int frames = 0, annotated = 0, with_object = 0;
  int width = 0, height = 0;
  double tolerance = 0;
  std::vector<VideoScores> modes;  // tracking, then detection alone
};

// Checks every input (manifest, models, frame files) before the first
// detection; frames must share one size.
Status evaluate_video(const VideoEvalOptions& options, VideoResults& results,
                      const ProgressFn& progress = {});

// The scores as a table (stdout of the command) and as one JSON object.
std::string video_text(const VideoResults& results);
std::string video_json(const VideoResults& results);

}  // namespace kg
