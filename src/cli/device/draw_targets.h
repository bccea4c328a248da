// The pictures `keygraph detect --draw` writes, one per scene, planned and
// checked before the first scene is read: a --draw that cannot be written
// fails at once, and nothing is drawn before it.
//   --draw DIR   an existing directory, or a name ending in '/': one
//                picture per scene, DIR/<scene stem><dir_ext>
//   --draw FILE  a file name with an extension this build writes: FILE for
//                one scene; FILE_<scene stem> beside it for several
//                (draw_paths(), command_line.h: the older spelling)
#pragma once

#include <functional>
#include <string>
#include <vector>

namespace kg::cli {

// Fills `out` with the picture of each scene, in order. `dir_ext`: the
// extension of pictures written into a directory (".png", ".pgm");
// `writable(path)`: whether this build writes a picture of that name. Each
// picture is checked as platform::OutputFile checks outputs (its directory
// exists and takes a file, it is not a device, FIFO or directory, it is not
// one of `inputs`) by creating its temporary and removing it again. Returns
// the error message (starting with "--draw"), or empty.
std::string plan_drawings(const std::string& draw, const std::vector<std::string>& scenes,
                          const std::string& dir_ext,
                          const std::function<bool(const std::string&)>& writable,
                          const std::vector<std::string>& inputs, std::vector<std::string>& out);

}  // namespace kg::cli
