#include "cli/device/stop_signal.h"

#include <signal.h>

#include <cstdio>

namespace kg::cli {

namespace {

volatile sig_atomic_t g_received = 0;
struct sigaction g_old_int, g_old_term, g_old_pipe;

extern "C" void on_stop_signal(int signal) {
  g_received = signal;
}

}  // namespace

StopSignal::StopSignal() {
  g_received = 0;
  struct sigaction sa {};
  sa.sa_handler = on_stop_signal;
  sigemptyset(&sa.sa_mask);
  // No SA_RESTART: a blocking wait returns EINTR and the loop looks at the
  // flag. SA_RESETHAND: the next signal has the default effect.
  sa.sa_flags = SA_RESETHAND;
  sigaction(SIGINT, &sa, &g_old_int);
  sigaction(SIGTERM, &sa, &g_old_term);
  struct sigaction ignore {};
  ignore.sa_handler = SIG_IGN;
  sigemptyset(&ignore.sa_mask);
  sigaction(SIGPIPE, &ignore, &g_old_pipe);
}

StopSignal::~StopSignal() {
  sigaction(SIGINT, &g_old_int, nullptr);
  sigaction(SIGTERM, &g_old_term, nullptr);
  sigaction(SIGPIPE, &g_old_pipe, nullptr);
}

int StopSignal::received() {
  return g_received;
}

const char* StopSignal::name(int signal) {
  if (signal == SIGINT) return "SIGINT";
  if (signal == SIGTERM) return "SIGTERM";
  static char buf[24];
  std::snprintf(buf, sizeof(buf), "signal %d", signal);
  return buf;
}

}  // namespace kg::cli
