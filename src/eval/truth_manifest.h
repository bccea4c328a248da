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

#include <cstddef>
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

// Bounds of a manifest (docs/EVAL.md): a regular file of at most
// kMaxManifestBytes, lines of at most kMaxManifestLineBytes, JSON nested at
// most kMaxJsonDepth levels (builder/strict_json.h).
inline constexpr std::size_t kMaxManifestBytes = std::size_t{64} << 20;
inline constexpr std::size_t kMaxManifestLineBytes = std::size_t{1} << 20;

// One line's JSON (strict_json.h: no key twice). On failure `error` says
// what is wrong (no location).
bool parse_truth_line(std::string_view text, TruthScene& out, std::string& error);

// A whole manifest's text; blank lines and lines starting with '#' are
// skipped; scene paths are resolved against `path`'s directory. Errors are
// "MANIFEST:LINE: what". Scene files are not checked.
Status parse_truth_manifest(std::string_view text, const std::string& path, TruthManifest& out);
// Reads the manifest file (a regular file within the bounds above), then
// parse_truth_manifest().
Status read_truth_manifest(const std::string& path, TruthManifest& out);

// Checks the scene's model names (instances and search) against the known
// models; the error names the first unknown one.
bool check_truth_models(const TruthScene& scene, const std::vector<std::string>& known,
                        std::string& error);

}  // namespace kg
