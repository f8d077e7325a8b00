#include "io/cloud/ply_io.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "common/atomic_file.h"
#include "common/error.h"

namespace cenote::io {
namespace {

static_assert(std::endian::native == std::endian::little, "PLY writer assumes a little-endian host");

constexpr size_t kBytesPerPoint = 3 * sizeof(float) + 3;
constexpr std::array<uint8_t, 3> kGrey = {128, 128, 128};
constexpr size_t kWriteBehindBytes = size_t{8} << 20;
// Points packed and written per write(): 240 KiB, so the packed bytes are still in the core's
// cache when the kernel copies them into the page cache (a whole 4 MB frame at once went through
// memory twice).
constexpr size_t kChunkPoints = 16384;

// The header of every PLY cenote writes. `comments` are whole lines; triangles adds the face element.
std::string plyHeader(const std::string& comments, size_t vertices, size_t triangles) {
  std::string text = "ply\nformat binary_little_endian 1.0\n" + comments;
  text += "element vertex " + std::to_string(vertices) + "\n";
  text += "property float x\nproperty float y\nproperty float z\n";
  text += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  if (triangles > 0) text += "element face " + std::to_string(triangles) + "\nproperty list uchar int vertex_indices\n";
  text += "end_header\n";
  return text;
}

// The streaming writer's header has a fixed size whatever the count: the count is right-aligned in
// a 20-digit field made of a comment line's padding, so close() can rewrite it in place.
std::string header(size_t count) {
  const std::string digits = std::to_string(count);
  return plyHeader("comment written by cenote\ncomment " + std::string(20 - digits.size(), '.') + "\n", count, 0);
}

void packPoint(char* dst, const Eigen::Vector3f& p, const std::array<uint8_t, 3>& rgb) {
  std::memcpy(dst, p.data(), 3 * sizeof(float));
  std::memcpy(dst + 3 * sizeof(float), rgb.data(), 3);
}

// Packs points [begin, end) of `batch` (colours, or grey) at `dst`, 15 bytes each, plus one byte of
// slack after the last. Each point is one 16-byte move (its xyz and the next point's x) and one
// 4-byte move (its RGB and the next red), whose extra bytes the next point overwrites; the batch's
// last point, whose next bytes lie past the vectors' ends, is moved exactly.
void packPoints(const PointBatch& batch, size_t begin, size_t end, char* dst) {
  static_assert(sizeof(Eigen::Vector3f) == 12 && sizeof(std::array<uint8_t, 3>) == 3);
  const bool colored = batch.hasColor();
  const uint8_t grey[4] = {kGrey[0], kGrey[1], kGrey[2], kGrey[0]};
  const size_t fast_end = std::min(end, batch.size() - 1);
  size_t i = begin;
  for (; i < fast_end; ++i, dst += kBytesPerPoint) {
    char xyz[16], rgb[4];
    std::memcpy(xyz, batch.points[i].data(), 16);
    std::memcpy(rgb, colored ? batch.colors[i].data() : grey, 4);
    std::memcpy(dst, xyz, 16);
    std::memcpy(dst + 12, rgb, 4);
  }
  for (; i < end; ++i, dst += kBytesPerPoint) packPoint(dst, batch.points[i], colored ? batch.colors[i] : kGrey);
}

}  // namespace

PlyWriter::PlyWriter(std::string path) : path_(std::move(path)), temp_path_(temporaryPathFor(path_)) {
  fd_ = ::open(temp_path_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd_ < 0) throwWriteError(path_, std::string("cannot create file (") + std::strerror(errno) + ")", errno);
  const std::string text = header(0);
  try {
    writeAll(text.data(), text.size());
  } catch (...) {
    ::close(fd_);
    throw;
  }
}

PlyWriter::~PlyWriter() {
  if (closed_) return;
  if (fd_ >= 0) ::close(fd_);
  detail::removeQuietly(temp_path_);
}

void PlyWriter::writeAll(const char* data, size_t size) {
  while (size > 0) {
    const ssize_t n = ::write(fd_, data, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int err = n < 0 ? errno : ENOSPC;
      throwWriteError(path_, std::string("write failed (") + std::strerror(err) + ")", err);
    }
    data += n;
    size -= static_cast<size_t>(n);
    written_bytes_ += static_cast<size_t>(n);
  }
}

void PlyWriter::writeBehind() {
  if (written_bytes_ - flushed_bytes_ < kWriteBehindBytes) return;
  // Best effort: a failure here only means the pages stay cached; write errors surface in write().
  ::sync_file_range(fd_, static_cast<off_t>(flushed_bytes_), static_cast<off_t>(written_bytes_ - flushed_bytes_),
                    SYNC_FILE_RANGE_WRITE);
  if (flushed_bytes_ > dropped_bytes_) {
    const auto start = static_cast<off_t>(dropped_bytes_), length = static_cast<off_t>(flushed_bytes_ - dropped_bytes_);
    ::sync_file_range(fd_, start, length, SYNC_FILE_RANGE_WAIT_BEFORE | SYNC_FILE_RANGE_WRITE | SYNC_FILE_RANGE_WAIT_AFTER);
    ::posix_fadvise(fd_, start, length, POSIX_FADV_DONTNEED);
    dropped_bytes_ = flushed_bytes_;
  }
  flushed_bytes_ = written_bytes_;
}

void PlyWriter::append(const PointBatch& batch) {
  if (batch.hasColor() && batch.colors.size() != batch.points.size()) {
    throw Error("PLY " + path_ + ": batch has " + std::to_string(batch.points.size()) + " points but " +
                std::to_string(batch.colors.size()) + " colours");
  }
  buffer_.resize(std::min(batch.size(), kChunkPoints) * kBytesPerPoint + 1);  // + packPoints' slack byte
  for (size_t begin = 0; begin < batch.size(); begin += kChunkPoints) {
    const size_t end = std::min(batch.size(), begin + kChunkPoints);
    packPoints(batch, begin, end, buffer_.data());
    writeAll(buffer_.data(), (end - begin) * kBytesPerPoint);
  }
  count_ += batch.size();
  writeBehind();
}

void PlyWriter::close() {
  if (closed_) return;
  const std::string text = header(count_);
  const bool header_written = ::pwrite(fd_, text.data(), text.size(), 0) == static_cast<ssize_t>(text.size());
  const int header_errno = errno;
  const bool closed = ::close(fd_) == 0;
  fd_ = -1;
  if (!header_written || !closed) {
    const int err = header_written ? errno : header_errno;
    throwWriteError(path_, std::string("write failed (") + std::strerror(err) + ")", err);
  }
  closed_ = true;  // commitTemporary removes the temporary file itself when it fails
  detail::commitTemporary(temp_path_, path_, Durability::kDurable);
}

void writePly(const std::string& path, const std::vector<Eigen::Vector3f>& points,
              const std::vector<std::array<uint8_t, 3>>& colors) {
  PointBatch batch;
  batch.points = points;
  batch.colors = colors;
  if (!colors.empty() && colors.size() != points.size()) {
    throw Error("writePly " + path + ": " + std::to_string(points.size()) + " points but " + std::to_string(colors.size()) +
                " colours");
  }
  PlyWriter writer(path);
  writer.append(batch);
  writer.close();
}

void writePlyMesh(const std::string& path, const std::vector<Eigen::Vector3f>& points,
                  const std::vector<std::array<uint8_t, 3>>& colors, const std::vector<std::array<uint32_t, 3>>& triangles,
                  const std::string& comment) {
  if (!colors.empty() && colors.size() != points.size()) {
    throw Error("writePly " + path + ": " + std::to_string(points.size()) + " points but " + std::to_string(colors.size()) +
                " colours");
  }
  const auto check = [&](const std::ostream& out) {
    if (!out) throwWriteError(path, std::strerror(errno), errno);
  };
  writeAtomically(path, Durability::kDurable, [&](const std::string& temp) {
    std::ofstream out(temp, std::ios::binary);
    check(out);
    out << plyHeader("comment " + comment + "\n", points.size(), triangles.size());
    std::vector<char> vertex(kBytesPerPoint);
    for (size_t i = 0; i < points.size(); ++i) {
      packPoint(vertex.data(), points[i], colors.empty() ? kGrey : colors[i]);
      out.write(vertex.data(), static_cast<std::streamsize>(vertex.size()));
    }
    for (const auto& t : triangles) {
      const uint8_t three = 3;
      out.write(reinterpret_cast<const char*>(&three), 1);
      out.write(reinterpret_cast<const char*>(t.data()), 12);
    }
    out.flush();
    check(out);
  });
}

PlyPoints readPly(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throwReadError(path);
  std::string line;
  std::getline(in, line);
  if (line != "ply") throw Error(path + ": not a PLY file (first line is not 'ply')");
  long count = -1;
  std::vector<std::string> properties;
  bool binary_le = false;
  while (std::getline(in, line)) {
    if (line == "end_header") break;
    std::istringstream words(line);
    std::string keyword;
    words >> keyword;
    if (keyword == "format") {
      std::string format;
      words >> format;
      binary_le = format == "binary_little_endian";
      if (!binary_le) throw Error(path + ": PLY format '" + format + "' is not supported (binary_little_endian only)");
    } else if (keyword == "element") {
      std::string name;
      words >> name;
      if (name != "vertex") throw Error(path + ": PLY element '" + name + "' is not supported (vertices only)");
      words >> count;
      if (!words || count < 0) throw Error(path + ": PLY vertex count is not a number >= 0");
    } else if (keyword == "property") {
      std::string type, name;
      words >> type >> name;
      properties.push_back(type + " " + name);
    } else if (keyword != "comment" && keyword != "obj_info") {
      throw Error(path + ": unexpected PLY header line '" + line + "'");
    }
  }
  if (line != "end_header") throw Error(path + ": PLY header has no end_header");
  const std::vector<std::string> expected = {"float x", "float y", "float z", "uchar red", "uchar green", "uchar blue"};
  if (!binary_le || count < 0 || properties != expected) {
    throw Error(path + ": PLY layout is not 'float x y z, uchar red green blue' binary little-endian vertices");
  }
  // The count is checked against the bytes the file holds before anything is allocated.
  const auto header_end = static_cast<uint64_t>(in.tellg());
  std::error_code size_error;
  const uint64_t file_bytes = std::filesystem::file_size(path, size_error);
  if (size_error) throw IoError("cannot read " + path + ": " + size_error.message());
  const uint64_t data_bytes = file_bytes - header_end;
  if (static_cast<uint64_t>(count) > data_bytes / kBytesPerPoint) {
    throw IoError(path + ": PLY header's element vertex count " + std::to_string(count) + " needs " +
                  (static_cast<uint64_t>(count) > UINT64_MAX / kBytesPerPoint
                       ? std::string("more bytes than there are")
                       : std::to_string(static_cast<uint64_t>(count) * kBytesPerPoint) + " bytes") +
                  " but the file holds " + std::to_string(data_bytes) + " after its header (truncated?)");
  }
  PlyPoints result;
  result.points.resize(count);
  result.colors.resize(count);
  std::vector<char> buffer(static_cast<size_t>(count) * kBytesPerPoint);
  in.read(buffer.data(), static_cast<std::streamsize>(buffer.size()));
  if (in.gcount() != static_cast<std::streamsize>(buffer.size())) {
    throw Error(path + ": PLY file is truncated (" + std::to_string(count) + " vertices announced)");
  }
  for (long i = 0; i < count; ++i) {
    const char* src = buffer.data() + i * kBytesPerPoint;
    std::memcpy(result.points[i].data(), src, 3 * sizeof(float));
    std::memcpy(result.colors[i].data(), src + 3 * sizeof(float), 3);
  }
  return result;
}

}  // namespace cenote::io
