#include "common/atomic_file.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>

namespace cenote {
namespace {

namespace fs = std::filesystem;

constexpr std::string_view kTempMarker = ".tmp-";

// Fsyncs the file or directory at `path`; the errno of the failure, 0 on success.
int syncPath(const std::string& path, bool directory) {
  const int fd = ::open(path.c_str(), (directory ? O_RDONLY | O_DIRECTORY : O_RDONLY) | O_CLOEXEC);
  if (fd < 0) return errno;
  const int err = ::fsync(fd) == 0 ? 0 : errno;
  ::close(fd);
  return err;
}

}  // namespace

std::string temporaryPathFor(const std::string& path) {
  const fs::path p(path);
  const std::string name = p.stem().string() + std::string(kTempMarker) + std::to_string(::getpid()) +
                           p.extension().string();
  return (p.parent_path() / name).string();
}

bool isTemporaryPath(const std::string& path) {
  const std::string stem = fs::path(path).stem().string();
  const size_t at = stem.rfind(kTempMarker);
  if (at == std::string::npos || at + kTempMarker.size() == stem.size()) return false;
  for (size_t i = at + kTempMarker.size(); i < stem.size(); ++i) {
    if (stem[i] < '0' || stem[i] > '9') return false;
  }
  return true;
}

namespace detail {

void removeQuietly(const std::string& temp) noexcept {
  std::error_code ec;
  fs::remove(temp, ec);
}

void commitTemporary(const std::string& temp, const std::string& path, Durability durability) {
  if (durability == Durability::kDurable) {
    if (const int err = syncPath(temp, false)) {
      removeQuietly(temp);
      throwWriteError(path, std::string("write failed (") + std::strerror(err) + ")", err);
    }
  }
  if (::rename(temp.c_str(), path.c_str()) != 0) {
    const int err = errno;
    removeQuietly(temp);
    throwWriteError(path, std::error_code(err, std::generic_category()).message(), err);
  }
  if (durability == Durability::kDurable) {
    const fs::path parent = fs::path(path).parent_path();
    // The file is in place; a directory that cannot be synced (some file systems refuse) only
    // weakens the guarantee, so it is not an error.
    syncPath(parent.empty() ? "." : parent.string(), true);
  }
}

}  // namespace detail

void writeFileAtomically(const std::string& path, std::string_view contents, Durability durability) {
  const std::string temp = temporaryPathFor(path);
  const int fd = ::open(temp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throwWriteError(path, "cannot create file", errno);
  const char* data = contents.data();
  size_t left = contents.size();
  int err = 0;
  while (left > 0) {
    const ssize_t n = ::write(fd, data, left);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      err = n < 0 ? errno : ENOSPC;
      break;
    }
    data += n;
    left -= static_cast<size_t>(n);
  }
  if (::close(fd) != 0 && err == 0) err = errno;
  if (err != 0) {
    detail::removeQuietly(temp);
    throwWriteError(path, "write failed (disk full?)", err);
  }
  detail::commitTemporary(temp, path, durability);
}

}  // namespace cenote
