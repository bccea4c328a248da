// Error reporting without exceptions: functions that can fail return a
// Status (or fill an output and return one). A Status carries a code and a
// short static or owned message suitable for a single line on stderr.
#pragma once

#include <string>
#include <utility>

namespace kg {

enum class StatusCode {
  kOk = 0,
  kInvalidArgument,
  kNotFound,
  kIoError,
  kCorruptData,
  kUnsupportedVersion,
  kResourceExhausted,
};

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
