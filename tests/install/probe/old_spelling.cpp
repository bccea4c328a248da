// The include spelling CMake users had before <keygraph/platform/...>: it
// keeps working through the targets' include directories.
#include "platform/files/file_source.h"
#include "platform/v4l2/v4l2_source.h"

int old_spelling_compiles() {
  return kg::platform::file_source_uses_opencv() ? 1 : 0;
}
