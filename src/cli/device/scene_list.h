// The scenes of a command line (keygraph detect): each argument an image
// file, or a directory standing for its image files.
#pragma once

#include <string>
#include <vector>

namespace kg::cli {

// Fills `out` with `args` in order, each directory replaced by its image
// files (platform::list_image_files(): by extension, sorted by name).
// Returns the error message, or empty: a directory that cannot be listed
// or holds no image file. Files are not opened here.
std::string expand_scene_paths(const std::vector<std::string>& args, std::vector<std::string>& out);

}  // namespace kg::cli
