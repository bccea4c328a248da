// kg_status names, the per-thread last error message and the version.
#include <cstring>

#include "capi/handles.h"

// The C numbers are kg::StatusCode's (both stable, appended to only).
#define KG_SAME_CODE(c, k) \
  static_assert(static_cast<int>(c) == static_cast<int>(kg::StatusCode::k), #c)
KG_SAME_CODE(KG_OK, kOk);
KG_SAME_CODE(KG_INVALID_ARGUMENT, kInvalidArgument);
KG_SAME_CODE(KG_NOT_FOUND, kNotFound);
KG_SAME_CODE(KG_IO_ERROR, kIoError);
KG_SAME_CODE(KG_CORRUPT_DATA, kCorruptData);
KG_SAME_CODE(KG_UNSUPPORTED_VERSION, kUnsupportedVersion);
KG_SAME_CODE(KG_RESOURCE_EXHAUSTED, kResourceExhausted);
KG_SAME_CODE(KG_TIMEOUT, kTimeout);
KG_SAME_CODE(KG_END_OF_STREAM, kEndOfStream);
KG_SAME_CODE(KG_BAD_FRAME, kBadFrame);
#undef KG_SAME_CODE

namespace {

// The last error of this thread, NUL-terminated; a fixed buffer so that
// recording one never allocates.
constexpr std::size_t kMessageSize = 512;
thread_local char t_last_error[kMessageSize] = "";

void record(const char* message, std::size_t length) {
  if (length >= kMessageSize) length = kMessageSize - 1;
  std::memcpy(t_last_error, message, length);
  t_last_error[length] = '\0';
}

}  // namespace

namespace kg::capi {

kg_status fail(const Status& status) {
  record(status.message().data(), status.message().size());
  return static_cast<kg_status>(status.code());
}

kg_status fail(kg_status code, const char* message) {
  record(message, std::strlen(message));
  return code;
}

}  // namespace kg::capi

extern "C" {

const char* kg_status_name(kg_status status) {
  // A C caller may pass any int (C's enums are ints): read it as one, since
  // a value outside the enumerators is not a valid kg_status in C++ (UBSan's
  // enum check).
  static_assert(sizeof(kg_status) == sizeof(int), "kg_status is passed as a C int");
  int code = 0;
  std::memcpy(&code, &status, sizeof code);
  if (code < static_cast<int>(kg::StatusCode::kOk) ||
      code > static_cast<int>(kg::StatusCode::kBadFrame))
    return "Unknown";
  return kg::status_code_name(static_cast<kg::StatusCode>(code));
}

const char* kg_last_error(void) {
  return t_last_error;
}

const char* kg_version(void) {
  return KG_VERSION;
}

}  // extern "C"
