// <gatun/result.h>: the library version, Error and Result<T>.
// Part of the Gatun API; <gatun/gatun.h> includes every part and says how errors, ownership and
// threads work for all of them.
#pragma once

#include <optional>
#include <string>
#include <utility>

namespace gatun {

/*-************************************
 *  Version
 **************************************/

/*! version() :
 *  @return the library's version, "MAJOR.MINOR.PATCH", the same as `gtn --version` of its build.
 *  The string is static: do not free it. */
const char* version();

/*-************************************
 *  Errors
 **************************************/

/*! ErrorCode : the kind of a failure. Each maps to the exit code of the `gtn` command (exitCode()). */
enum class ErrorCode {
  kOk = 0,        /* no error */
  kInvalidData,   /* the input is malformed or violates an invariant (exit code 1) */
  kUnsupported,   /* a valid input uses a feature Gatun rejects (exit code 1) */
  kNotOurFile,    /* the content is not the format it was read as, e.g. no .gtn magic (exit code 1) */
  kVersionTooNew, /* a newer major version of the .gtn format (exit code 1) */
  kUsage,         /* the caller asked for something impossible: a missing level, a bad option (exit code 2) */
  kIo,            /* a file could not be opened, read or written (exit code 3) */
};

/*! Error : the outcome of an operation that returns no value.
 *  ok() is true on success (code kOk, empty message). On failure, message() is what `gtn` prints
 *  after "gtn: ", e.g. "cube.gtn: byte offset 96: truncated: ...". */
class Error {
 public:
  Error() = default;
  Error(ErrorCode code, std::string message) : code_(code), message_(std::move(message)) {}

  bool ok() const { return code_ == ErrorCode::kOk; }
  ErrorCode code() const { return code_; }
  const std::string& message() const { return message_; }
  /*! exitCode() : the exit code `gtn` ends with for this error: 0, 1 (invalid data), 2 (usage), 3 (I/O). */
  int exitCode() const;

 private:
  ErrorCode code_ = ErrorCode::kOk;
  std::string message_;
};

/*! Result<T> : a value of type T, or the Error that prevented it.
 *  ok() says which. value() returns the value; called on a failed result it throws
 *  std::bad_optional_access. error() is the failure (ok() when there was none). */
template <class T>
class Result {
 public:
  Result(T value) : value_(std::move(value)) {}      // NOLINT: implicit by design
  Result(Error error) : error_(std::move(error)) {}  // NOLINT: implicit by design; `error` must not be ok()

  bool ok() const { return value_.has_value(); }
  const Error& error() const { return error_; }
  T& value() & { return value_.value(); }
  const T& value() const& { return value_.value(); }
  T&& value() && { return std::move(value_.value()); }

 private:
  Error error_;
  std::optional<T> value_;
};

}  // namespace gatun
