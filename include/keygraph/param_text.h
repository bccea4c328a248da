// Pipeline parameters by name, as `keygraph build --set`, `keygraph detect
// --set` and the bindings spell them ("graph.max_anisotropy=2.5",
// "ransac.seed=7"), and the named configurations (presets) of `keygraph
// build --preset`. Names are the fields of keygraph/params.h as
// GROUP.FIELD (keypoints, graph, descriptor, ransac, views); enumerations
// take their names ("hessian", "int8", "strongest").
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "keygraph/params.h"
#include "keygraph/status.h"

namespace kg {

// Sets the parameter `name` of `params` from its text. Unknown names and
// values that do not parse are errors (kInvalidArgument, `params`
// unchanged); ranges are checked by the consumer (keygraph build, the
// Detector's options) on the whole set, since some limits couple fields.
Status set_param(Params& params, std::string_view name, std::string_view value);
// The same from "NAME=VALUE".
Status set_param(Params& params, std::string_view assignment);

// The value of parameter `name` as set_param() reads it ("40", "hessian");
// false for an unknown name.
bool param_value_text(const Params& params, std::string_view name, std::string& out);

// Every parameter name, in the order the index stores them.
std::vector<std::string> param_names();

// Named configurations. Each is a complete Params: the defaults with the
// preset's fields changed (docs/RESULTS.md measures each).
//   "defaults"  Params{}: tilted views at 45 degrees in one level, the
//               triangle check, circuit completion, near-neighbour arcs.
//   "frontal"   no tilted views, no triangle check or circuit completion,
//               arcs between every pair in range, 20 search leaves: the
//               cheapest frame, for objects seen face on.
//   "angled"    ASIFT's tilts to 60 degrees in two levels, the triangle
//               check, circuit completion, arcs between every pair in range,
//               10 search leaves: a little more recall at an angle for about
//               1.5x the default frame.
Params frontal_params(Params base = Params{});
Params angled_params(Params base = Params{});
// The preset called `name` applied to `base` ("defaults" returns Params{});
// kInvalidArgument for an unknown name.
Status preset_params(std::string_view name, Params& out);
// The preset names, for help texts.
std::vector<std::string> preset_names();

}  // namespace kg
