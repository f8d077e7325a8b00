// error.h: the one exception type that cenote's libraries throw, and its kind.
// A message says what was wrong, where, and what was allowed, e.g.
//   "stereo: right image is 800x599 but left is 800x600"
// The kind says whose fault it is and what a caller can do about it; server/wire/status_error.h maps
// each kind to one gRPC status code (the only place that does). A plain Error is bad input
// (kInvalidArgument); the derived types below set the other kinds (and are what the functions
// below throw), so `catch (const Error&)` still catches everything, `catch (const IoError&)` only
// what it names, and code that maps errors switches on kind().
// Library code never ends the process; the command-line programs catch Error, print it and exit non-zero.
// Threads: plain values.
#pragma once

#include <stdexcept>
#include <string>

namespace cenote {

enum class ErrorKind {
  kInvalidArgument,     // the input itself is wrong (a config value, a malformed file, a bad pose)
  kNotFound,            // a file or directory that was asked for does not exist
  kResourceExhausted,   // a limit was reached: a configured limit, the map's extent, a full disk
  kIoFailure,           // a file exists (or was to be written) but reading or writing it failed
  kFailedPrecondition,  // the input is fine but the state does not allow it now (e.g. not calibrated yet)
};

// "invalid argument", "not found", "resource exhausted", "I/O failure", "failed precondition".
const char* toString(ErrorKind kind);

class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message, ErrorKind kind = ErrorKind::kInvalidArgument)
      : std::runtime_error(message), kind_(kind) {}
  ErrorKind kind() const { return kind_; }

 private:
  ErrorKind kind_;
};

// An Error of one fixed kind. The typed names below are this template, one instance per kind: each is
// its own type to catch (`catch (const IoError&)`), and each sets its kind (`IoError::kKind`).
template <ErrorKind Kind>
class KindedError : public Error {
 public:
  static constexpr ErrorKind kKind = Kind;
  explicit KindedError(const std::string& message) : Error(message, Kind) {}
};

using NotFoundError = KindedError<ErrorKind::kNotFound>;
using ResourceExhaustedError = KindedError<ErrorKind::kResourceExhausted>;
using IoError = KindedError<ErrorKind::kIoFailure>;
using FailedPreconditionError = KindedError<ErrorKind::kFailedPrecondition>;

// The kind of a failed read or write from its errno: ENOSPC, EDQUOT and EFBIG (disk, quota or
// file-size limit full) are kResourceExhausted, ENOENT kNotFound when `missing_is_not_found` (reads; a write into a missing
// directory is an I/O failure), anything else kIoFailure.
ErrorKind ioErrorKind(int errno_value, bool missing_is_not_found = false);

// Throws "cannot write <path>: <reason>": ResourceExhaustedError when errno_value is ENOSPC or
// EDQUOT, IoError otherwise (also when errno_value is 0).
[[noreturn]] void throwWriteError(const std::string& path, const std::string& reason, int errno_value = 0);

// For a file that could not be opened for reading: throws NotFoundError "cannot read <what><path>:
// no such file" when it does not exist, IoError "cannot read <what><path>: <unreadable>" when it
// does. @param what e.g. "trajectory " or "image ", empty for none.
[[noreturn]] void throwReadError(const std::string& path, const std::string& unreadable = "permission denied",
                                 const std::string& what = "");

}  // namespace cenote
