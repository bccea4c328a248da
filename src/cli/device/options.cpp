#include "cli/device/options.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>

namespace kg::cli {

namespace {

// The column where option help starts, unless the option's names are wider.
constexpr std::size_t kHelpColumn = 28;
// The width the help is wrapped to.
constexpr std::size_t kHelpWidth = 80;

bool is_option(const std::string& arg) {
  return arg.size() > 1 && arg[0] == '-';
}

// The end of the options: every later argument is positional.
bool is_end_of_options(const std::string& arg) {
  return arg == "--";
}

bool is_help(const std::string& arg) {
  return arg == "-h" || arg == "--help";
}

std::vector<std::string> split_names(const std::string& names) {
  std::vector<std::string> out;
  std::stringstream in(names);
  for (std::string name; std::getline(in, name, ',');) {
    const std::size_t first = name.find_first_not_of(' ');
    if (first != std::string::npos) out.push_back(name.substr(first));
  }
  return out;
}

// Shortest text of `v` that reads back as `v` (defaults in the help: 10,
// 0.2, 1000000).
std::string number_text(double v) {
  char buf[32];
  if (v == std::floor(v) && std::fabs(v) < 1e15) {
    std::snprintf(buf, sizeof(buf), "%.0f", v);
    return buf;
  }
  for (int digits = 1; digits <= 17; ++digits) {
    std::snprintf(buf, sizeof(buf), "%.*g", digits, v);
    if (std::strtod(buf, nullptr) == v) break;
  }
  return buf;
}

// `text` broken into lines of at most `width` characters at spaces (a
// longer word stays whole). Line breaks in `text` count as spaces: they
// only keep the source lines short.
std::vector<std::string> wrap(const std::string& text, std::size_t width) {
  std::vector<std::string> lines(1);
  std::stringstream words(text);
  for (std::string word; words >> word;) {
    std::string& line = lines.back();
    if (!line.empty() && line.size() + 1 + word.size() > width) {
      lines.push_back(word);
    } else {
      line += (line.empty() ? "" : " ") + word;
    }
  }
  return lines;
}

}  // namespace

Options::Options(std::string command, std::string synopsis, std::string summary)
    : command_(std::move(command)), synopsis_(std::move(synopsis)), summary_(std::move(summary)) {}

Options& Options::add(const std::string& names, Kind kind, const std::string& value_name,
                      const std::string& help, Apply apply, const std::string& default_text) {
  options_.push_back(
      {split_names(names), value_name, help, default_text, kind, std::move(apply), {}});
  return *this;
}

Options& Options::flag(const std::string& names, bool& target, const std::string& help) {
  return add(names, Kind::kFlag, {}, help,
             [&target](const std::string&) {
               target = true;
               return std::string();
             },
             {});
}

Options& Options::flag(const std::string& names, const std::string& help,
                       std::function<void()> action) {
  return add(names, Kind::kFlag, {}, help,
             [action = std::move(action)](const std::string&) {
               action();
               return std::string();
             },
             {});
}

Options& Options::text(const std::string& names, const std::string& value_name, std::string& target,
                       const std::string& help) {
  return add(
      names, Kind::kValue, value_name, help,
      [&target](const std::string& v) {
        target = v;
        return std::string();
      },
      target);
}

Options& Options::integer(const std::string& names, const std::string& value_name, int& target,
                          int min, int max, const std::string& help) {
  const std::string name = split_names(names).back();
  add(
      names, Kind::kValue, value_name, help,
      [&target, name, min, max](const std::string& v) {
        if (parse_int(v, min, max, target)) return std::string();
        return name + " " + v + ": not a whole number in " + std::to_string(min) + ".." +
               std::to_string(max);
      },
      std::to_string(target));
  options_.back().range = std::to_string(min) + ".." + std::to_string(max);
  return *this;
}

Options& Options::unsigned64(const std::string& names, const std::string& value_name,
                             std::uint64_t& target, const std::string& help) {
  const std::string name = split_names(names).back();
  return add(
      names, Kind::kValue, value_name, help,
      [&target, name](const std::string& v) {
        std::uint64_t value = 0;
        const char* end = v.data() + v.size();
        const auto [ptr, ec] = std::from_chars(v.data(), end, value);
        if (v.empty() || ec != std::errc() || ptr != end)
          return name + " " + v + ": not a whole number in 0.." + std::to_string(~std::uint64_t{0});
        target = value;
        return std::string();
      },
      std::to_string(target));
}

Options& Options::number(const std::string& names, const std::string& value_name, double& target,
                         double min, double max, bool above_min, const std::string& help) {
  const std::string name = split_names(names).back();
  std::string range = above_min ? "(" : "[";
  range += number_text(min) + ", " + number_text(max) + "]";
  add(
      names, Kind::kValue, value_name, help,
      [&target, name, min, max, above_min, range](const std::string& v) {
        char* end = nullptr;
        const double value = std::strtod(v.c_str(), &end);
        const bool whole = !v.empty() && end == v.c_str() + v.size() &&
                           v.find_first_of(" \t\n") == std::string::npos;
        if (!whole || !std::isfinite(value) || value < min || value > max ||
            (above_min && value == min))
          return name + " " + v + ": not a number in " + range;
        target = value;
        return std::string();
      },
      number_text(target));
  options_.back().range = range;
  return *this;
}

Options& Options::value(const std::string& names, const std::string& value_name,
                        const std::string& help, Apply apply, const std::string& default_text) {
  return add(names, Kind::kValue, value_name, help, std::move(apply), default_text);
}

Options& Options::optional_value(const std::string& names, const std::string& value_name,
                                 const std::string& help, Apply apply) {
  return add(names, Kind::kOptionalValue, value_name, help, std::move(apply), {});
}

Options& Options::positional(const std::string& value_name, const std::string& help, Apply apply) {
  positional_name_ = value_name;
  positional_help_ = help;
  positional_ = std::move(apply);
  return *this;
}

Options& Options::repeatable() {
  if (!options_.empty()) options_.back().repeatable = true;
  return *this;
}

Options& Options::note(const std::string& text) {
  notes_.push_back(text);
  return *this;
}

Options& Options::example(const std::string& command_line) {
  examples_.push_back(command_line);
  return *this;
}

const Options::Option* Options::find(const std::string& name) const {
  for (const Option& o : options_) {
    for (const std::string& n : o.names) {
      if (n == name) return &o;
    }
  }
  return nullptr;
}

int Options::parse(const Args& args) const {
  // Help first, wherever it is before `--` (a value such as `--name -h` is
  // not help): `keygraph build --bogus --help` shows the help, not an error.
  for (std::size_t i = 0; i < args.size() && !is_end_of_options(args[i]); ++i) {
    if (is_help(args[i])) {
      std::fputs(help().c_str(), stdout);
      return 0;
    }
    const Option* o = find(args[i]);
    if (o == nullptr) continue;
    if (o->kind == Kind::kValue ||
        (o->kind == Kind::kOptionalValue && i + 1 < args.size() && !is_option(args[i + 1])))
      ++i;
  }
  std::vector<const Option*> given;  // the value options seen so far
  bool options_ended = false;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    std::string error;
    if (!options_ended && is_end_of_options(a)) {
      options_ended = true;
      continue;
    }
    if (options_ended || !is_option(a)) {
      if (!positional_) return usage_error("unexpected argument " + a);
      error = positional_(a);
    } else if (const Option* o = find(a); o == nullptr) {
      return usage_error("unknown option " + a);
    } else if (o->kind == Kind::kFlag) {
      error = o->apply({});
    } else if (!o->repeatable && std::find(given.begin(), given.end(), o) != given.end()) {
      return usage_error(a + " given twice (it takes one value)");
    } else if (o->kind == Kind::kOptionalValue) {
      given.push_back(o);
      const bool value_given = i + 1 < args.size() && !is_option(args[i + 1]);
      error = o->apply(value_given ? args[++i] : std::string());
    } else if (i + 1 >= args.size()) {
      error = a + " needs a value";
    } else {
      given.push_back(o);
      error = o->apply(args[++i]);
    }
    if (!error.empty()) {
      std::fprintf(stderr, "keygraph: %s: %s\n", command_.c_str(), one_line(error).c_str());
      return kUsageError;
    }
  }
  return -1;
}

int Options::usage_error(const std::string& message) const {
  std::fprintf(stderr, "keygraph: %s: %s (see keygraph %s --help)\n", command_.c_str(),
               one_line(message).c_str(), command_.c_str());
  return kUsageError;
}

std::string Options::help() const {
  std::string out = "usage: keygraph " + command_ + " " + synopsis_ + "\n" + summary_ + "\n";
  // One row per option (and the positional argument): its names and value,
  // then its help, continuation lines indented to the help column.
  struct Row {
    std::string left, help;
  };
  std::vector<Row> rows;
  if (positional_) rows.push_back({positional_name_, positional_help_});
  for (const Option& o : options_) {
    std::string left;
    for (const std::string& n : o.names) left += (left.empty() ? "" : ", ") + n;
    if (o.kind == Kind::kValue) left += " " + o.value_name;
    if (o.kind == Kind::kOptionalValue) left += " [" + o.value_name + "]";
    std::string help = o.help;
    if (o.repeatable) help += " (repeatable)";
    if (!o.range.empty() || !o.default_text.empty()) {
      help += " (";
      if (!o.range.empty()) help += o.range + (o.default_text.empty() ? "" : "; ");
      if (!o.default_text.empty()) help += "default: " + o.default_text;
      help += ")";
    }
    rows.push_back({left, help});
  }
  if (positional_) {
    rows.push_back({"--", "end of the options: every later argument is " + positional_name_ +
                              ", also one that starts with '-'"});
  }
  rows.push_back({"-h, --help", "print this help and exit"});
  std::size_t width = 0;
  for (const Row& r : rows) {
    if (r.left.size() + 4 <= kHelpColumn) width = std::max(width, r.left.size());
  }
  const std::string indent(width + 4, ' ');
  out += "\narguments and options:\n";
  for (const Row& r : rows) {
    std::string line = "  " + r.left;
    if (r.left.size() > width) {
      out += line + "\n";
      line = indent;
    } else {
      line += std::string(width - r.left.size() + 2, ' ');
    }
    bool first = true;
    for (const std::string& part : wrap(r.help, kHelpWidth - indent.size())) {
      out += (first ? line : indent) + part + "\n";
      first = false;
    }
  }
  for (const std::string& n : notes_) out += "\n" + n + "\n";
  if (!examples_.empty()) {
    out += "\nexample" + std::string(examples_.size() > 1 ? "s" : "") + ":\n";
    for (const std::string& e : examples_) out += "  " + e + "\n";
  }
  return out;
}

bool asks_for_help(const Args& args) {
  for (const std::string& a : args) {
    if (is_end_of_options(a)) break;
    if (is_help(a)) return true;
  }
  return false;
}

}  // namespace kg::cli
