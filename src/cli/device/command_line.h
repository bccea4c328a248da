// What every keygraph subcommand shares: its arguments, the one-line error
// convention and strict number parsing. No OpenCV (see CMakeLists.txt).
#pragma once

#include <string>
#include <vector>

namespace kg::cli {

using Args = std::vector<std::string>;

// "keygraph: <message>" on stderr; returns 1.
int fail(const std::string& message);

// Whole-string decimal integers in [min, max]; false on anything else
// (signs, spaces, trailing characters, overflow).
bool parse_int(const std::string& text, int min, int max, int& out);
// "WIDTHxHEIGHT", both in 1..32768.
bool parse_size(const std::string& text, int& width, int& height);

}  // namespace kg::cli
