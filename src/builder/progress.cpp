#include "builder/progress.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>

namespace kg {

namespace {

// A terminal line is rewritten at most this often (seconds): fast loops
// would otherwise spend their time writing to the terminal.
constexpr double kRedrawInterval = 0.1;
// `what` is cut to this many characters, so that the line fits a terminal.
constexpr std::size_t kMaxWhat = 32;

double steady_seconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

}  // namespace

bool is_terminal(std::FILE* stream) {
  return ::isatty(::fileno(stream)) == 1;
}

ProgressReporter::ProgressReporter(Settings settings, std::FILE* out, Clock clock)
    : settings_(std::move(settings)),
      out_(out),
      clock_(clock ? std::move(clock) : Clock(steady_seconds)),
      start_(clock_()) {}

ProgressReporter::~ProgressReporter() {
  finish();
}

std::string ProgressReporter::duration(double seconds) {
  const long total = std::lround(std::max(0.0, seconds));
  const long h = total / 3600, m = total / 60 % 60, s = total % 60;
  char buf[32];
  if (h > 0) {
    std::snprintf(buf, sizeof(buf), "%ld:%02ld:%02ld", h, m, s);
  } else {
    std::snprintf(buf, sizeof(buf), "%ld:%02ld", m, s);
  }
  return buf;
}

std::string ProgressReporter::line(const Settings& settings, int done, int total,
                                   const std::string& what, double elapsed_s) {
  std::string out = settings.task + ": ";
  if (!settings.unit.empty()) out += settings.unit + " ";
  out += std::to_string(done) + "/" + std::to_string(total);
  if (!what.empty()) {
    out += " " + (what.size() > kMaxWhat ? what.substr(0, kMaxWhat - 3) + "..." : what);
  }
  const int percent = total > 0 ? static_cast<int>(100.0 * done / total) : 0;
  out += " (" + std::to_string(percent) + " %)";
  if (done > 0 && done < total) {
    out += ", " + duration(elapsed_s / done * (total - done)) + " left";
  } else if (done >= total && total > 0) {
    out += ", took " + duration(elapsed_s);
  }
  return out;
}

void ProgressReporter::update(int done, int total, const std::string& what) {
  if (out_ == nullptr || total <= 0) return;
  const double now = clock_();
  if (settings_.terminal) {
    if (done < total && last_shown_ >= 0 && now - last_shown_ < kRedrawInterval) return;
    last_shown_ = now;
    const std::string text = line(settings_, done, total, what, now - start_);
    // Spaces over the rest of a longer previous line.
    const std::size_t pad = shown_width_ > text.size() ? shown_width_ - text.size() : 0;
    std::fprintf(out_, "\r%s%*s", text.c_str(), static_cast<int>(pad), "");
    std::fflush(out_);
    shown_width_ = text.size();
    return;
  }
  const int tenth = static_cast<int>(10.0 * done / total);
  if (!settings_.every_step && tenth == last_tenth_) return;
  last_tenth_ = tenth;
  std::fprintf(out_, "%s\n", line(settings_, done, total, what, now - start_).c_str());
  std::fflush(out_);
}

void ProgressReporter::finish() {
  if (out_ == nullptr || shown_width_ == 0) return;
  std::fprintf(out_, "\r%*s\r", static_cast<int>(shown_width_), "");
  std::fflush(out_);
  shown_width_ = 0;
}

ProgressFn ProgressReporter::callback() {
  return [this](int done, int total, const std::string& what) { update(done, total, what); };
}

}  // namespace kg
