#include "mapping/history/frame_store.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>

#include "common/error.h"

namespace cenote::mapping::history {
namespace {

namespace fs = std::filesystem;

std::string systemError() { return std::strerror(errno); }

// The sections' files: SEQ.points, SEQ.updates, and SEQ.marched while the updates are resampled.
constexpr const char* kPoints = "points";
constexpr const char* kUpdates = "updates";
constexpr const char* kMarched = "marched";

// Writes `bytes` to `path` through a temporary file renamed over it: a reader sees the old file or
// the new one. @throws as FrameStore::put, `path` then as it was.
void writeFile(const std::string& path, const std::string& bytes) {
  const std::string tmp = path + ".tmp";
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw IoError("frame store: cannot create " + tmp + ": " + systemError());
  size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int error = n == 0 ? EIO : errno;
      ::close(fd);
      ::unlink(tmp.c_str());
      if (error == ENOSPC) throw ResourceExhaustedError("frame store: disk full writing " + tmp);
      throw IoError("frame store: cannot write " + tmp + ": " + std::strerror(error));
    }
    done += static_cast<size_t>(n);
  }
  ::close(fd);
  if (::rename(tmp.c_str(), path.c_str()) != 0) {
    const std::string why = systemError();
    ::unlink(tmp.c_str());
    throw IoError("frame store: cannot rename " + tmp + ": " + why);
  }
}

}  // namespace

FrameStore::FrameStore(const std::string& dir, uint64_t max_bytes) : max_bytes_(max_bytes) {
  if (dir.empty()) {
    std::string pattern = (fs::temp_directory_path() / "cenote-frames-XXXXXX").string();
    if (::mkdtemp(pattern.data()) == nullptr) {
      throw IoError("frame store: cannot create a folder " + pattern + " in the temp folder: " + systemError());
    }
    dir_ = pattern;
    own_dir_ = true;
  } else {
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (!fs::is_directory(dir)) {
      throw IoError("frame store: map.history_dir " + dir + " cannot be created" + (ec ? ": " + ec.message() : ""));
    }
    dir_ = dir;
  }
}

FrameStore::~FrameStore() {
  clear();
  if (own_dir_) {
    std::error_code ec;
    fs::remove(dir_, ec);
  }
}

std::string FrameStore::pathOf(uint32_t seq, const char* section) const {
  return dir_ + "/" + std::to_string(seq) + "." + section;
}

const FrameStore::Entry& FrameStore::entryOf(uint32_t seq) const {
  const auto it = frames_.find(seq);
  if (it == frames_.end()) throw NotFoundError("frame store: frame " + std::to_string(seq) + " is not in the store");
  return it->second;
}

const FrameMeta& FrameStore::meta(uint32_t seq) const { return entryOf(seq).meta; }

void FrameStore::put(uint32_t seq, const FrameMeta& meta, const std::string& points, const std::string& updates) {
  if (contains(seq)) throw Error("frame store: frame " + std::to_string(seq) + " is already in the store");
  writeFile(pathOf(seq, kPoints), points);
  try {
    writeFile(pathOf(seq, kUpdates), updates);
  } catch (...) {
    ::unlink(pathOf(seq, kPoints).c_str());
    throw;
  }
  Entry& entry = frames_[seq];
  entry.meta = meta;
  entry.points_bytes = points.size();
  entry.updates_bytes = updates.size();
  bytes_ += points.size() + updates.size();
}

void FrameStore::putUpdates(uint32_t seq, const FrameMeta& meta, const std::string& updates) {
  entryOf(seq);  // @throws NotFoundError
  writeFile(pathOf(seq, kUpdates), updates);
  Entry& entry = frames_[seq];
  if (entry.marched_bytes != 0) {
    ::unlink(pathOf(seq, kMarched).c_str());
    bytes_ -= entry.marched_bytes;
    entry.marched_bytes = 0;
  }
  bytes_ += updates.size() - entry.updates_bytes;
  entry.meta = meta;
  entry.updates_bytes = updates.size();
}

void FrameStore::putResampled(uint32_t seq, const FrameMeta& meta, const std::string& updates) {
  entryOf(seq);  // @throws NotFoundError
  Entry& entry = frames_[seq];
  const std::string path = pathOf(seq, kUpdates), marched = pathOf(seq, kMarched);
  // The first resampling keeps the marched updates aside (a rename: no bytes copied).
  const bool keep_marched = entry.marched_bytes == 0;
  if (keep_marched && ::rename(path.c_str(), marched.c_str()) != 0) {
    throw IoError("frame store: cannot rename " + path + ": " + systemError());
  }
  try {
    writeFile(path, updates);
  } catch (...) {
    if (keep_marched) ::rename(marched.c_str(), path.c_str());
    throw;
  }
  if (keep_marched) {
    entry.marched_bytes = entry.updates_bytes;
    entry.updates_bytes = 0;
  }
  bytes_ += updates.size() - entry.updates_bytes;
  entry.meta = meta;
  entry.updates_bytes = updates.size();
}

std::string FrameStore::readSection(uint32_t seq, const char* section, uint64_t size) const {
  const std::string path = pathOf(seq, section);
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw IoError("frame store: cannot open " + path + ": " + systemError());
  std::string out(size, '\0');
  size_t done = 0;
  while (done < size) {
    const ssize_t n = ::pread(fd, out.data() + done, size - done, static_cast<off_t>(done));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const std::string why = n == 0 ? "it is shorter than written" : systemError();
      ::close(fd);
      throw IoError("frame store: cannot read " + path + ": " + why);
    }
    done += static_cast<size_t>(n);
  }
  ::close(fd);
  return out;
}

std::string FrameStore::readPoints(uint32_t seq) const { return readSection(seq, kPoints, entryOf(seq).points_bytes); }

std::string FrameStore::readUpdates(uint32_t seq) const { return readSection(seq, kUpdates, entryOf(seq).updates_bytes); }

std::string FrameStore::readMarched(uint32_t seq) const {
  const Entry& entry = entryOf(seq);
  return entry.marched_bytes != 0 ? readSection(seq, kMarched, entry.marched_bytes)
                                  : readSection(seq, kUpdates, entry.updates_bytes);
}

void FrameStore::unlinkAll(uint32_t seq, const Entry& entry) const {
  ::unlink(pathOf(seq, kPoints).c_str());
  ::unlink(pathOf(seq, kUpdates).c_str());
  if (entry.marched_bytes != 0) ::unlink(pathOf(seq, kMarched).c_str());
}

void FrameStore::erase(uint32_t seq) {
  const auto it = frames_.find(seq);
  if (it == frames_.end()) return;
  bytes_ -= it->second.points_bytes + it->second.updates_bytes + it->second.marched_bytes;
  unlinkAll(seq, it->second);
  frames_.erase(it);
}

void FrameStore::clear() {
  for (const auto& [seq, entry] : frames_) unlinkAll(seq, entry);
  frames_.clear();
  bytes_ = 0;
}

std::vector<uint32_t> FrameStore::overBudget() const {
  std::vector<uint32_t> out;
  uint64_t bytes = bytes_;
  for (auto it = frames_.begin(); it != frames_.end() && bytes > max_bytes_; ++it) {
    out.push_back(it->first);
    bytes -= it->second.points_bytes + it->second.updates_bytes + it->second.marched_bytes;
  }
  return out;
}

}  // namespace cenote::mapping::history
