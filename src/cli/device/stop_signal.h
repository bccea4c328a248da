// Ctrl-C for long-running commands (live): while a StopSignal exists,
// SIGINT and SIGTERM only set a flag that the frame loop checks between
// frames, so the current frame is finished, the camera is stopped and the
// command exits normally. The handler is one-shot: a second Ctrl-C gets the
// default action and ends a process that is stuck. SIGPIPE is ignored, so a
// closed stdout shows up as a write error the loop can stop on.
#pragma once

namespace kg::cli {

class StopSignal {
 public:
  StopSignal();   // installs the handlers
  ~StopSignal();  // restores the previous ones
  StopSignal(const StopSignal&) = delete;
  StopSignal& operator=(const StopSignal&) = delete;

  // The signal that asked to stop, or 0.
  static int received();
  // "SIGINT", "SIGTERM" or "signal N".
  static const char* name(int signal);
};

}  // namespace kg::cli
