// A command's options as one table that both parses the arguments and
// writes the command's --help, so that the help cannot drift from the
// parser: each option is declared once with its names, value, help text
// and the variable (or action) it sets; its default is that variable's
// value when the option is declared.
//
// Arguments are taken in order, so that an option may apply to the
// positional argument that follows it (`keygraph build --name N M.png`).
// An option that takes a value may be given once, unless it is declared
// repeatable() (--set; build's --name and --roi, which apply to the next
// model); a flag given twice is the same as once. `--` ends the options:
// every later argument is positional, also one that starts with '-'.
// A usage error (an unknown option, a missing or bad value, a value option
// given twice) is one line on stderr and exit code 2; -h or --help anywhere
// before `--` prints the help on stdout and exit code 0.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "cli/device/command_line.h"

namespace kg::cli {

// The exit code of a usage error; runtime failures exit 1 (fail()).
constexpr int kUsageError = 2;

class Options {
 public:
  // Applies an option's value (empty for a flag); returns an error message
  // (after the option's name and value on the error line), or empty.
  using Apply = std::function<std::string(const std::string& value)>;

  // `command`: as typed after "keygraph" ("build", "eval"); `synopsis`:
  // the usage line after the command; `summary`: what the command does.
  Options(std::string command, std::string synopsis, std::string summary);

  // `names`: "--index" or "-o, --output". `help` is wrapped to the help's
  // width (its own line breaks count as spaces).
  Options& flag(const std::string& names, bool& target, const std::string& help);
  Options& flag(const std::string& names, const std::string& help, std::function<void()> action);
  Options& text(const std::string& names, const std::string& value_name, std::string& target,
                const std::string& help);
  // Whole decimal numbers in [min, max] (parse_int()).
  Options& integer(const std::string& names, const std::string& value_name, int& target, int min,
                   int max, const std::string& help);
  Options& unsigned64(const std::string& names, const std::string& value_name,
                      std::uint64_t& target, const std::string& help);
  // Finite numbers in [min, max], or in (min, max] when `above_min`.
  Options& number(const std::string& names, const std::string& value_name, double& target,
                  double min, double max, bool above_min, const std::string& help);
  // Any other value; `default_text` is shown as the default when not empty.
  Options& value(const std::string& names, const std::string& value_name, const std::string& help,
                 Apply apply, const std::string& default_text = {});
  // A value that may be left out: taken when the next argument does not
  // start with '-'.
  Options& optional_value(const std::string& names, const std::string& value_name,
                          const std::string& help, Apply apply);
  // Marks the option declared last as repeatable: each use applies its value
  // (the help says "repeatable").
  Options& repeatable();
  // Every argument that is not an option, in order (none when not set).
  Options& positional(const std::string& value_name, const std::string& help, Apply apply);
  // A paragraph after the options, and example command lines.
  Options& note(const std::string& text);
  Options& example(const std::string& command_line);

  // Parses `args`. Returns -1 when the command should go on; otherwise the
  // exit code: 0 after the help was printed, kUsageError after an error line.
  int parse(const Args& args) const;
  // The whole help text (what --help prints).
  std::string help() const;
  // "keygraph: COMMAND: message (see keygraph COMMAND --help)"; returns
  // kUsageError.
  int usage_error(const std::string& message) const;

 private:
  enum class Kind { kFlag, kValue, kOptionalValue };
  struct Option {
    std::vector<std::string> names;
    std::string value_name, help, default_text;
    Kind kind = Kind::kFlag;
    Apply apply;
    std::string range;  // of a number: "1..20", "(0, 100]"
    bool repeatable = false;
  };
  Options& add(const std::string& names, Kind kind, const std::string& value_name,
               const std::string& help, Apply apply, const std::string& default_text);
  const Option* find(const std::string& name) const;

  std::string command_, synopsis_, summary_;
  std::vector<Option> options_;
  std::string positional_name_, positional_help_;
  Apply positional_;
  std::vector<std::string> notes_, examples_;
};

// True when `args` holds -h or --help: for a command with several tables
// (eval's modes), which prints them all.
bool asks_for_help(const Args& args);

}  // namespace kg::cli
