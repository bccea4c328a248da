// The ground truth of a video (`keygraph eval --video`, docs/EVAL.md): the
// manifest of `eval --truth` (eval/truth_manifest.h) with one line per
// frame, in the order the camera delivered them. A line without
// "instances" is a frame without ground truth: it is processed (a tracker
// needs every frame) but not scored.
//
//   {"scene": "frames/0000.jpg", "instances": [{"model": "exit-right",
//    "corners": [[x, y], [x, y], [x, y], [x, y]]}]}
//   {"scene": "frames/0001.jpg"}
//   {"scene": "frames/0002.jpg", "instances": []}
//
// The last line is a frame where none of the models shows (scored: any
// detection there is wrong). A comment line "# part: NAME" names the part
// of the video the frames after it belong to (eval --video scores each
// part too).
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "eval/truth_manifest.h"
#include "keygraph/status.h"

namespace kg {

struct VideoManifest {
  TruthManifest truth;            // every frame, in order
  std::vector<bool> annotated;    // per frame: whether it has ground truth
  std::vector<std::string> part;  // per frame: the last "# part:" before it, or ""
};

// Parses the text (errors "MANIFEST:LINE: what"); scene paths resolve
// against `path`'s directory. Frame files are not checked.
Status parse_video_manifest(std::string_view text, const std::string& path, VideoManifest& out);
// Reads the file (the bounds of read_truth_manifest()), then parses it.
Status read_video_manifest(const std::string& path, VideoManifest& out);

}  // namespace kg
