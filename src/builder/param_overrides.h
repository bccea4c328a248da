// Setting pipeline parameters by name ("graph.max_anisotropy=2.5"), for the
// command line's --set option and evaluation sweeps.
#pragma once

#include <string>
#include <vector>

#include "keygraph/params.h"
#include "keygraph/status.h"

namespace kg {

// Applies "name=value"; the result is validated as a whole by the caller
// (format::validate_params). Unknown names and unparsable values are errors.
Status apply_param_override(const std::string& assignment, Params& params);

// The value of parameter `name` as --set spells it ("40", "hessian"), for
// help texts' defaults; false for an unknown name.
bool param_value_text(const Params& params, const std::string& name, std::string& out);

// Names accepted by apply_param_override (every stored parameter, in file
// order), for help texts.
std::vector<std::string> param_names();

// The opt-in for many signs seen at an angle (README, "Results";
// docs/RESULTS.md, "Circuit completion"): `base` with tilted views to 60
// degrees in 2 levels, the triangle check at 0.6, circuit completion, model
// arcs between every pair in range (as measured) and 10 search leaves per
// query.
Params angled_params(Params base = Params{});

// The frontal configuration (the defaults of format 6.4, and the cheapest
// frame): `base` without tilted views, triangle check or circuit
// completion, with model arcs between every pair in range and 20 search
// leaves per query.
Params frontal_params(Params base = Params{});

}  // namespace kg
