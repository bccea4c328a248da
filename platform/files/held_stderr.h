// Image decoders (libpng, libjpeg, libtiff) print their own complaints on
// stderr. While a StderrHold holds, whatever the process writes on stderr
// (descriptor 2) goes to a temporary file instead; release() restores
// stderr and passes the text on only when asked: on failure the caller's
// one error line replaces it, on success it is shown (e.g. libpng's
// warnings about sRGB profiles). Not for threads that log meanwhile.
#pragma once

#include <cstdio>

namespace kg::platform {

class StderrHold {
 public:
  StderrHold() = default;
  ~StderrHold();  // releases (passing the text on) and removes the file
  StderrHold(const StderrHold&) = delete;
  StderrHold& operator=(const StderrHold&) = delete;

  // Starts holding; does nothing when already holding or when no
  // temporary file can be made (stderr then stays as it is).
  void hold();
  // Restores stderr; with `pass_on`, writes the held text to it first.
  void release(bool pass_on);

 private:
  std::FILE* file_ = nullptr;  // kept for the next hold()
  int saved_ = -1;             // the real stderr while holding
};

}  // namespace kg::platform
