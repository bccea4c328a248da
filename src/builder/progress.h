// A long command's progress on stderr: on a terminal one line rewritten in
// place ("build: model 12/50 exit-left (24 %), 0:31 left") and cleared at
// the end; elsewhere (a log file, a pipe) a plain line at every step or
// about every 10 %, so that logs stay short. The loops of the builder and the evaluation take a
// ProgressFn and know nothing of terminals.
#pragma once

#include <cstdio>
#include <functional>
#include <string>

namespace kg {

// `done` of `total` steps are finished; `what`: the step just finished.
using ProgressFn = std::function<void(int done, int total, const std::string& what)>;

class ProgressReporter {
 public:
  // Seconds on a monotonic clock (injected by the tests).
  using Clock = std::function<double()>;
  struct Settings {
    std::string task;         // "build", "eval"
    std::string unit;         // "model", "frame"; may be empty
    bool terminal = false;    // rewrite one line in place
    bool every_step = false;  // plain lines: one per step instead of per ~10 %
  };

  // Reports to `out` (not owned). `clock` defaults to std::chrono::steady_clock.
  ProgressReporter(Settings settings, std::FILE* out, Clock clock = {});
  ~ProgressReporter();  // finish()
  ProgressReporter(const ProgressReporter&) = delete;
  ProgressReporter& operator=(const ProgressReporter&) = delete;

  void update(int done, int total, const std::string& what);
  // Clears the terminal line (before results or an error are printed).
  void finish();
  // update() as a ProgressFn (valid while this reporter lives).
  ProgressFn callback();

  // "build: model 12/50 exit-left (24 %), 0:31 left": the time left is the
  // elapsed time per finished step times the steps left (none before the
  // first step is done).
  static std::string line(const Settings& settings, int done, int total, const std::string& what,
                          double elapsed_s);
  // "0:31", "12:05", "1:02:03" (rounded to the second).
  static std::string duration(double seconds);

 private:
  Settings settings_;
  std::FILE* out_;
  Clock clock_;
  double start_ = 0;
  double last_shown_ = -1;       // terminal: when the line was last rewritten
  int last_tenth_ = -1;          // plain lines: the last tenth of the work shown
  std::size_t shown_width_ = 0;  // terminal: characters of the line shown
};

// True when `stream` is a terminal (isatty).
bool is_terminal(std::FILE* stream);

}  // namespace kg
