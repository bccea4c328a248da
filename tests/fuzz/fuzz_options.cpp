// libFuzzer target for the command line's value parsers: strict integers
// (parse_int), WIDTHxHEIGHT (parse_size), --set NAME=VALUE
// (set_param, then the whole parameter set validated as the
// index writer does) and --draw file names (draw_paths). Each input is
// split at NUL bytes into arguments. A parsed value must be within its range
// and print back as the text it came from (leading zeros aside).
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "cli/device/command_line.h"
#include "core/index/index_format.h"
#include "keygraph/param_text.h"

namespace {

// A decimal number's text without leading zeros ("007" reads as 7).
std::string canonical(const std::string& digits) {
  const std::size_t first = digits.find_first_not_of('0');
  return first == std::string::npos ? "0" : digits.substr(first);
}

void require(bool ok, const char* what) {
  if (!ok) {
    std::fprintf(stderr, "fuzz_options: %s\n", what);
    std::abort();
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::vector<std::string> args(1);
  for (std::size_t i = 0; i < size; ++i) {
    if (data[i] == 0) {
      args.emplace_back();
    } else {
      args.back() += static_cast<char>(data[i]);
    }
  }
  for (const std::string& a : args) {
    int value = 0;
    if (kg::cli::parse_int(a, 1, 1 << 30, value)) {
      require(value >= 1 && value <= (1 << 30), "parse_int out of range");
      require(std::to_string(value) == canonical(a), "parse_int: value differs from its text");
    }
    int w = 0, h = 0;
    if (kg::cli::parse_size(a, w, h)) {
      require(w >= 1 && w <= 32768 && h >= 1 && h <= 32768, "parse_size out of range");
      const std::size_t x = a.find('x');
      require(std::to_string(w) == canonical(a.substr(0, x)) &&
                  std::to_string(h) == canonical(a.substr(x + 1)),
              "parse_size: values differ from the text");
    }
    kg::Params params;
    if (kg::set_param(params, a)) (void)kg::format::validate_params(params);
  }
  if (args.size() >= 2) {
    std::vector<std::string> scenes(args.begin() + 1, args.end());
    std::vector<std::string> drawn;
    const std::string error = kg::cli::draw_paths(args[0], scenes, drawn);
    if (error.empty()) {
      require(drawn.size() == scenes.size(), "draw_paths: one path per scene");
      for (std::size_t i = 0; i < drawn.size(); ++i) {
        for (std::size_t j = 0; j < i; ++j)
          require(drawn[i] != drawn[j] || scenes[i] == scenes[j], "two scenes drawn to one file");
      }
    }
  }
  return 0;
}
