#include "common/error.h"

#include <cerrno>
#include <filesystem>

#include "common/enum_names.h"

namespace cenote {

const char* toString(ErrorKind kind) {
  constexpr EnumName<ErrorKind> kNames[] = {{ErrorKind::kInvalidArgument, "invalid argument"},
                                            {ErrorKind::kNotFound, "not found"},
                                            {ErrorKind::kResourceExhausted, "resource exhausted"},
                                            {ErrorKind::kIoFailure, "I/O failure"},
                                            {ErrorKind::kFailedPrecondition, "failed precondition"}};
  return enumName(kNames, kind, "unknown");
}

ErrorKind ioErrorKind(int errno_value, bool missing_is_not_found) {
  // EFBIG too: a file size limit (RLIMIT_FSIZE, `ulimit -f`) or the file system's largest file was reached.
  if (errno_value == ENOSPC || errno_value == EDQUOT || errno_value == EFBIG) return ErrorKind::kResourceExhausted;
  if (errno_value == ENOENT && missing_is_not_found) return ErrorKind::kNotFound;
  return ErrorKind::kIoFailure;
}

void throwWriteError(const std::string& path, const std::string& reason, int errno_value) {
  const std::string message = "cannot write " + path + ": " + reason;
  if (ioErrorKind(errno_value) == ErrorKind::kResourceExhausted) throw ResourceExhaustedError(message);
  throw IoError(message);
}

void throwReadError(const std::string& path, const std::string& unreadable, const std::string& what) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw NotFoundError("cannot read " + what + path + ": no such file");
  throw IoError("cannot read " + what + path + ": " + unreadable);
}

}  // namespace cenote
