// What every keygraph subcommand shares: its arguments, the one-line error
// convention and strict number parsing. No OpenCV (see CMakeLists.txt).
#pragma once

#include <string>
#include <vector>

namespace kg::cli {

using Args = std::vector<std::string>;

// The command being run ("build", "live"; main() sets it): every error line
// names it, as "keygraph: build: ...".
void set_command_name(const std::string& name);

// "keygraph: <command>: <message>" on stderr, on one line (one_line(); the
// command left out when the message already starts with it, or none is
// set); returns 1.
int fail(const std::string& message);
// `message` with control characters escaped as in JSON (\n, \u001b): a
// name from an input file or the command line that holds a newline keeps
// an error on one line.
std::string one_line(const std::string& message);

// "1 model", "2 models": a count and its noun, plural unless it is one.
std::string counted(long long n, const std::string& noun);

// Whole-string decimal integers in [min, max]; false on anything else
// (signs, spaces, trailing characters, overflow).
bool parse_int(const std::string& text, int min, int max, int& out);
// "WIDTHxHEIGHT", both in 1..32768.
bool parse_size(const std::string& text, int& width, int& height);

// The --draw file of each scene: `draw` itself for one scene; with several,
// OUT_<scene stem><ext> for --draw OUT<ext>. Returns an error message when
// two scenes would be drawn to one file (same stem in two directories), or
// a picture's path is a scene or not a regular file (checked before the
// first scene), else empty.
std::string draw_paths(const std::string& draw, const std::vector<std::string>& scenes,
                       std::vector<std::string>& out);

// To call when stdout was closed by its reader (EPIPE), a normal way to
// stop: check_stdout() then neither writes nor reports.
void stdout_closed_by_reader();
// Flushes stdout and checks that everything written to it arrived. Returns
// `exit_code`, or 1 after one error line when the command succeeded but its
// output was lost (e.g. a full disk).
int check_stdout(int exit_code);

}  // namespace kg::cli
