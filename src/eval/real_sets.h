// Ground-truth manifests (eval/truth_manifest.h) for the three real photo
// sets of ../shared/data/real (its README.md): their own formats converted,
// the images referenced in place (paths relative to the manifest's
// directory), never copied. `keygraph manifest` writes them.
#pragma once

#include <string>
#include <vector>

#include "keygraph/status.h"

namespace kg {

struct ConvertedSet {
  std::string manifest;             // JSON lines
  std::string models_json;          // models.json for the set's models (empty: none)
  std::string summary;              // what was kept, for the user
  std::vector<std::string> inputs;  // every file the set's conversion read or names
};

// Each reads its set's text files within the bounds of eval/set_files.h.
//
// exit-signs/: corners.txt, every sign acceptable as "exit-left" or
// "exit-right" (the arrow is not annotated). Frames within 30 s of the two
// model source frames are left out. split "dev" / "test" keeps alternate
// bursts (frames closer than 5 s to the previous one belong to its burst),
// starting with the first burst for dev; "" keeps every burst.
// "model-bursts" keeps only the frames left out, instead: a sanity check
// (a method should find the signs its models were cropped from), never a score.
Status convert_exit_signs(const std::string& dir, const std::string& manifest_path,
                          const std::string& split, ConvertedSet& out);

// planar-pairs/: image A of each pair is the model (named after the pair),
// image B the scene with the pair's A-to-B homography, searched with its
// own model only ("search").
Status convert_planar_pairs(const std::string& dir, const std::string& manifest_path,
                            ConvertedSet& out);

// negatives/: every image, with no instances.
Status convert_negatives(const std::string& dir, const std::string& manifest_path,
                         ConvertedSet& out);

}  // namespace kg
