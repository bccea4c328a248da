#include "cli/device/command_line.h"

#include <charconv>
#include <cstdio>

namespace kg::cli {

int fail(const std::string& message) {
  std::fprintf(stderr, "keygraph: %s\n", message.c_str());
  return 1;
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

}  // namespace kg::cli
