// atomic_file.h: writing a file so that it appears whole or not at all: the contents go to a
// temporary file in the same directory, which is renamed over the target at the end. A crash or a
// failed write never leaves half a file under the target's name, and never leaves the temporary
// one behind when the failure is seen (it is removed on every error path).
// Temporary names are `<stem>.tmp-<pid><ext>` ("map.vdb" -> "map.tmp-4242.vdb"): writers that
// choose their format from the extension (cv::imwrite, cv::FileStorage) see the right one, and a
// later start-up can recognise stale ones with isTemporaryPath().
// Durability::kDurable also fsyncs the file before the rename and the directory after it, so the
// new file survives a power cut (snapshots, calibration, reports); kFast skips both (outputs
// written every frame, whose loss on a power cut costs nothing).
// Errors: "cannot write <path>: <reason>", an IoError, or ResourceExhaustedError when the disk or
// quota is full (common/error.h).
// Threads: independent calls; two writers of the same path in one process race (the last rename wins).
#pragma once

#include <cerrno>
#include <exception>
#include <string>
#include <string_view>

#include "common/error.h"

namespace cenote {

enum class Durability { kDurable, kFast };

// `<dir>/<stem>.tmp-<pid><ext>` for `<dir>/<stem><ext>`.
std::string temporaryPathFor(const std::string& path);
// Whether a file name has the form temporaryPathFor() gives (any pid).
bool isTemporaryPath(const std::string& path);

namespace detail {
// Fsyncs `temp` (kDurable), renames it over `path`, fsyncs the directory (kDurable).
// @throws Error (throwWriteError) after removing `temp` when any step fails.
void commitTemporary(const std::string& temp, const std::string& path, Durability durability);
void removeQuietly(const std::string& temp) noexcept;
}  // namespace detail

// Calls `write(temp_path)`, which creates and fills the file, then commits it over `path`.
// An Error thrown by `write` propagates unchanged; any other std::exception becomes
// throwWriteError(path, e.what(), errno): ResourceExhaustedError when the library's failure left ENOSPC
// or EDQUOT in errno, an IoError otherwise. The temporary file is removed on every failure.
template <typename Write>
void writeAtomically(const std::string& path, Durability durability, Write&& write) {
  const std::string temp = temporaryPathFor(path);
  errno = 0;
  try {
    write(temp);
  } catch (const Error&) {
    detail::removeQuietly(temp);
    throw;
  } catch (const std::exception& e) {
    detail::removeQuietly(temp);
    throwWriteError(path, e.what(), errno);  // a full disk keeps its kind through libraries that only say "write failed"
  }
  detail::commitTemporary(temp, path, durability);
}

// Writes `contents` as the whole file. Failures: "cannot write <path>: cannot create file" and
// "cannot write <path>: write failed (disk full?)", as the writers this replaced said.
void writeFileAtomically(const std::string& path, std::string_view contents, Durability durability);

}  // namespace cenote
