#include "platform/files/signal_cleanup.h"

#include <signal.h>
#include <unistd.h>

#include <climits>
#include <cstring>

namespace kg::platform::cleanup {

namespace {

constexpr int kFileSlots = 8;
constexpr int kCreatedDirs = 8;
constexpr int kDigits = 8;

char g_files[kFileSlots][PATH_MAX];
volatile sig_atomic_t g_file_used[kFileSlots];

char g_staging[PATH_MAX];
char g_created[kCreatedDirs][PATH_MAX];
volatile sig_atomic_t g_created_count = 0;
volatile sig_atomic_t g_staged_count = 0;
volatile sig_atomic_t g_staging_used = 0;
char g_scratch[PATH_MAX + kDigits + 2];  // the handler's path buffer

bool g_handlers_installed = false;

// Async-signal-safe: unlink and rmdir only, paths built by hand.
void remove_staging() {
  const std::size_t n = std::strlen(g_staging);
  std::memcpy(g_scratch, g_staging, n);
  g_scratch[n] = '/';
  for (sig_atomic_t i = 0; i < g_staged_count; ++i) {
    long v = i;
    for (int d = kDigits - 1; d >= 0; --d, v /= 10)
      g_scratch[n + 1 + d] = static_cast<char>('0' + v % 10);
    g_scratch[n + 1 + kDigits] = '\0';
    ::unlink(g_scratch);
  }
  ::rmdir(g_staging);
  for (sig_atomic_t i = g_created_count; i > 0; --i) ::rmdir(g_created[i - 1]);
}

extern "C" void remove_temporaries(int signal) {
  for (int i = 0; i < kFileSlots; ++i) {
    if (g_file_used[i]) ::unlink(g_files[i]);
  }
  if (g_staging_used) remove_staging();
  // The signal's default action, so the exit status says how it ended.
  ::signal(signal, SIG_DFL);
  ::raise(signal);
}

void install_handlers() {
  if (g_handlers_installed) return;
  g_handlers_installed = true;
  for (const int sig : {SIGINT, SIGTERM, SIGHUP, SIGPIPE}) {
    struct sigaction old {};
    if (::sigaction(sig, nullptr, &old) != 0 || old.sa_handler != SIG_DFL) continue;
    struct sigaction sa {};
    sa.sa_handler = remove_temporaries;
    sigemptyset(&sa.sa_mask);
    ::sigaction(sig, &sa, nullptr);
  }
}

bool copy_path(char* to, const std::string& path) {
  if (path.size() >= PATH_MAX || path.find('\0') != std::string::npos) return false;
  std::memcpy(to, path.c_str(), path.size() + 1);
  return true;
}

}  // namespace

int register_file(const std::string& path) {
  install_handlers();
  for (int i = 0; i < kFileSlots; ++i) {
    if (g_file_used[i]) continue;
    if (!copy_path(g_files[i], path)) return -1;
    g_file_used[i] = 1;
    return i;
  }
  return -1;
}

void unregister_file(int slot) {
  if (slot >= 0 && slot < kFileSlots) g_file_used[slot] = 0;
}

bool register_staging(const std::string& dir, const std::vector<std::string>& created) {
  if (g_staging_used || created.size() > kCreatedDirs) return false;
  install_handlers();
  if (!copy_path(g_staging, dir)) return false;
  for (std::size_t i = 0; i < created.size(); ++i) {
    if (!copy_path(g_created[i], created[i])) return false;
  }
  g_created_count = static_cast<sig_atomic_t>(created.size());
  g_staged_count = 0;
  g_staging_used = 1;
  return true;
}

void set_staged_count(std::size_t count) {
  g_staged_count = static_cast<sig_atomic_t>(count);
}

void unregister_staging() {
  g_staging_used = 0;
  g_staged_count = 0;
  g_created_count = 0;
}

std::string staged_name(std::size_t index) {
  std::string name(kDigits, '0');
  for (int d = kDigits - 1; d >= 0; --d, index /= 10)
    name[static_cast<std::size_t>(d)] = static_cast<char>('0' + index % 10);
  return name;
}

}  // namespace kg::platform::cleanup
