// Status and StatusOr: how every library layer reports failure (nothing below cli/ prints or exits).
#pragma once

#include <optional>
#include <string>
#include <utility>

namespace gtn {

enum class StatusCode {
  kOk = 0,
  kInvalidData,    // the input is malformed or violates an invariant (exit 1)
  kUnsupported,    // a valid input uses a feature we reject loudly (exit 1)
  kNotOurFile,     // the content is not the format we were asked to read (exit 1)
  kVersionTooNew,  // a newer major version of a format (exit 1)
  kUsage,          // the caller asked for something impossible (exit 2)
  kIo,             // a file could not be opened, read or written (exit 3)
};

// Process exit code the CLI uses for a status code (docs/design.md: 0, 1 invalid, 2 usage, 3 I/O).
int exitCodeFor(StatusCode code);

class [[nodiscard]] Status {
 public:
  Status() = default;
  Status(StatusCode code, std::string message) : code_(code), message_(std::move(message)) {}
  static Status ok() { return Status(); }

  bool isOk() const { return code_ == StatusCode::kOk; }
  StatusCode code() const { return code_; }
  const std::string& message() const { return message_; }

 private:
  StatusCode code_ = StatusCode::kOk;
  std::string message_;
};

inline Status invalidData(std::string m) { return Status(StatusCode::kInvalidData, std::move(m)); }
inline Status unsupported(std::string m) { return Status(StatusCode::kUnsupported, std::move(m)); }
inline Status ioError(std::string m) { return Status(StatusCode::kIo, std::move(m)); }
inline Status usageError(std::string m) { return Status(StatusCode::kUsage, std::move(m)); }

template <class T>
class [[nodiscard]] StatusOr {
 public:
  StatusOr(Status status) : status_(std::move(status)) {}  // NOLINT: implicit by design
  StatusOr(T value) : value_(std::move(value)) {}          // NOLINT: implicit by design

  bool isOk() const { return status_.isOk(); }
  const Status& status() const { return status_; }
  T& value() & { return *value_; }
  const T& value() const& { return *value_; }
  T&& value() && { return std::move(*value_); }
  T* operator->() { return &*value_; }
  const T* operator->() const { return &*value_; }
  T& operator*() & { return *value_; }

 private:
  Status status_;
  std::optional<T> value_;
};

#define GTN_CONCAT_INNER(a, b) a##b
#define GTN_CONCAT(a, b) GTN_CONCAT_INNER(a, b)

#define GTN_RETURN_IF_ERROR(expr)                \
  do {                                           \
    ::gtn::Status gtn_status_ = (expr);          \
    if (!gtn_status_.isOk()) return gtn_status_; \
  } while (0)

#define GTN_ASSIGN_OR_RETURN_IMPL(tmp, lhs, expr) \
  auto tmp = (expr);                              \
  if (!tmp.isOk()) return tmp.status();           \
  lhs = std::move(tmp).value()

#define GTN_ASSIGN_OR_RETURN(lhs, expr) GTN_ASSIGN_OR_RETURN_IMPL(GTN_CONCAT(gtn_statusor_, __LINE__), lhs, expr)

}  // namespace gtn
