// The ground-truth manifest of `keygraph eval --truth` (docs/EVAL.md): JSON
// lines, one scene each, with the model instances a person marked in it.
//
//   {"scene": "frames/0001.jpg", "instances": [{"model": "exit-left",
//    "corners": [[x, y], [x, y], [x, y], [x, y]]}]}
//   {"scene": "b.png", "search": ["adam"],
//    "instances": [{"model": "adam", "homography": [9 numbers]}]}
//
// OpenCV-free (the manifest fuzzer links it without the desktop build).
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "keygraph/status.h"
#include "keygraph/types.h"

namespace kg {

struct TruthInstance {
  // Acceptable model names: any of them found there counts (look-alike
  // models the annotation does not tell apart). Never empty.
  std::vector<std::string> models;
  // Either corners (any start and direction, a simple quadrilateral) or a
  // homography, model pixels -> scene pixels, normalised to h[8] = 1 (one
  // model name then: the outline comes from that model's size).
  bool has_homography = false;
  Point2f corners[4]{};
  Homography homography{};
};

struct TruthScene {
  int line = 0;                          // 1-based line in the manifest
  std::string scene;                     // as written
  std::string path;                      // resolved against the manifest's directory
  std::vector<TruthInstance> instances;  // empty: none of the models is there
  std::vector<std::string> search;       // the models to search it with; empty: all
};

struct TruthManifest {
  std::string path;
  std::vector<TruthScene> scenes;
};

// One line's JSON. On failure `error` says what is wrong (no location).
bool parse_truth_line(std::string_view text, TruthScene& out, std::string& error);

// Reads the whole manifest; blank lines and lines starting with '#' are
// skipped. Errors are "MANIFEST:LINE: what". Scene files are not checked.
Status read_truth_manifest(const std::string& path, TruthManifest& out);

// Checks the scene's model names (instances and search) against the known
// models; the error names the first unknown one.
bool check_truth_models(const TruthScene& scene, const std::vector<std::string>& known,
                        std::string& error);

}  // namespace kg
