#include "cli/device/command_line.h"

#include <cerrno>
#include <charconv>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <map>

#include "platform/files/output_file.h"

namespace kg::cli {

namespace {
std::string g_command;
}  // namespace

void set_command_name(const std::string& name) {
  g_command = name;
}

int fail(const std::string& message) {
  const std::string prefix = g_command.empty() ? std::string() : g_command + ": ";
  const bool named = prefix.empty() || message.compare(0, prefix.size(), prefix) == 0;
  std::fprintf(stderr, "keygraph: %s%s\n", named ? "" : prefix.c_str(), one_line(message).c_str());
  return 1;
}

std::string counted(long long n, const std::string& noun) {
  return std::to_string(n) + " " + noun + (n == 1 ? "" : "s");
}

std::string one_line(const std::string& message) {
  std::string out;
  out.reserve(message.size());
  for (const char ch : message) {
    const auto c = static_cast<unsigned char>(ch);
    if (c == '\n') {
      out += "\\n";
    } else if (c == '\r') {
      out += "\\r";
    } else if (c == '\t') {
      out += "\\t";
    } else if (c < 0x20 || c == 0x7f) {
      char code[8];
      std::snprintf(code, sizeof(code), "\\u%04x", c);
      out += code;
    } else {
      out += ch;
    }
  }
  return out;
}

bool parse_int(const std::string& text, int min, int max, int& out) {
  int value = 0;
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, value);
  if (text.empty() || ec != std::errc() || ptr != end || value < min || value > max) return false;
  out = value;
  return true;
}

bool parse_size(const std::string& text, int& width, int& height) {
  const std::size_t x = text.find('x');
  if (x == std::string::npos) return false;
  return parse_int(text.substr(0, x), 1, 32768, width) &&
         parse_int(text.substr(x + 1), 1, 32768, height);
}

std::string draw_paths(const std::string& draw, const std::vector<std::string>& scenes,
                       std::vector<std::string>& out) {
  namespace fs = std::filesystem;
  out.clear();
  std::map<std::string, const std::string*> drawn_from;
  for (const std::string& scene : scenes) {
    std::string path = draw;
    if (scenes.size() > 1) {
      const fs::path p(draw);
      path = (p.parent_path() /
              (p.stem().string() + "_" + fs::path(scene).stem().string() + p.extension().string()))
                 .string();
    }
    const auto [it, inserted] = drawn_from.emplace(path, &scene);
    if (!inserted && *it->second != scene) {
      return "--draw: " + *it->second + " and " + scene + " would both be drawn to " + path +
             "; give the scenes distinct names";
    }
    out.push_back(std::move(path));
  }
  // Every picture's path before the first scene: none may be a scene or be
  // in the way (a picture written before another is refused is partial
  // output).
  for (const std::string& path : out) {
    if (Status s = platform::check_output_target(path); !s) return "--draw " + s.message();
    for (const std::string& scene : scenes) {
      if (platform::same_file(path, scene))
        return "--draw " + path + ": is also an input (" + scene + "); choose another output";
    }
  }
  return {};
}

namespace {
bool g_stdout_closed = false;
}  // namespace

void stdout_closed_by_reader() {
  g_stdout_closed = true;
}

int check_stdout(int exit_code) {
  if (g_stdout_closed) return exit_code;
  errno = 0;
  const bool flushed = std::fflush(stdout) == 0;
  const int err = errno;
  if (flushed && !std::ferror(stdout)) return exit_code;
  if (exit_code != 0) return exit_code;  // the command's own error line stands
  return fail(std::string("cannot write to stdout") +
              (!flushed && err != 0 ? std::string(": ") + std::strerror(err) : "") +
              " (output lost)");
}

}  // namespace kg::cli
