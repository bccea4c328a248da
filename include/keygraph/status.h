// Error reporting without exceptions: functions that can fail return a
// Status (or fill an output and return one). A Status carries a code and a
// message of one line (no newline), suitable for stderr as it is. A Status
// is a value: copy it freely; its message is owned (constructing one with a
// message allocates, so the detector's per-frame path returns only
// messages it built before the frame, or codes with static text).
#pragma once

#include <string>
#include <utility>

namespace kg {

// The values are stable (the C API returns them as numbers): new codes are
// only ever appended.
enum class StatusCode {
  kOk = 0,
  kInvalidArgument,     // a bad parameter, option, frame or limit
  kNotFound,            // a missing file, device, camera or model
  kIoError,             // reading or writing failed
  kCorruptData,         // a malformed index or image
  kUnsupportedVersion,  // an index of a format version this build cannot read
  kResourceExhausted,   // a size or count beyond a limit, or out of memory
  // Frame sources (platform/frame_source.h): the non-fatal outcomes of next().
  kTimeout,      // no frame within the timeout; ask again
  kEndOfStream,  // a finite source (files) has no more frames
  kBadFrame,     // this one frame was unusable; the source keeps streaming
};

// The code's name without the k ("InvalidArgument"), for logs and bindings.
inline const char* status_code_name(StatusCode code) {
  switch (code) {
    case StatusCode::kOk:
      return "Ok";
    case StatusCode::kInvalidArgument:
      return "InvalidArgument";
    case StatusCode::kNotFound:
      return "NotFound";
    case StatusCode::kIoError:
      return "IoError";
    case StatusCode::kCorruptData:
      return "CorruptData";
    case StatusCode::kUnsupportedVersion:
      return "UnsupportedVersion";
    case StatusCode::kResourceExhausted:
      return "ResourceExhausted";
    case StatusCode::kTimeout:
      return "Timeout";
    case StatusCode::kEndOfStream:
      return "EndOfStream";
    case StatusCode::kBadFrame:
      return "BadFrame";
  }
  return "Unknown";
}

class [[nodiscard]] Status {
 public:
  Status() = default;
  Status(StatusCode code, std::string message) : code_(code), message_(std::move(message)) {}
  static Status ok() { return {}; }

  bool is_ok() const { return code_ == StatusCode::kOk; }
  explicit operator bool() const { return is_ok(); }
  StatusCode code() const { return code_; }
  const std::string& message() const { return message_; }

 private:
  StatusCode code_ = StatusCode::kOk;
  std::string message_;
};

}  // namespace kg
