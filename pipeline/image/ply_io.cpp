#include "pipeline/image/ply_io.h"

#include <bit>
#include <cstring>
#include <filesystem>
#include <sstream>

#include "common/error.h"

namespace cenote::pipeline {
namespace {

static_assert(std::endian::native == std::endian::little, "PLY writer assumes a little-endian host");

constexpr size_t kBytesPerPoint = 3 * sizeof(float) + 3;
constexpr std::array<uint8_t, 3> kGrey = {128, 128, 128};

// The header has a fixed size whatever the count: the count is right-aligned in a 20-digit field
// made of a comment line's padding, so close() can rewrite it in place.
std::string header(size_t count) {
  const std::string digits = std::to_string(count);
  std::string text = "ply\nformat binary_little_endian 1.0\ncomment written by cenote\n";
  text += "comment " + std::string(20 - digits.size(), '.') + "\n";
  text += "element vertex " + digits + "\n";
  text += "property float x\nproperty float y\nproperty float z\n";
  text += "property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n";
  return text;
}

void packPoint(char* dst, const Eigen::Vector3f& p, const std::array<uint8_t, 3>& rgb) {
  std::memcpy(dst, p.data(), 3 * sizeof(float));
  std::memcpy(dst + 3 * sizeof(float), rgb.data(), 3);
}

}  // namespace

PlyWriter::PlyWriter(std::string path) : path_(std::move(path)) {
  out_.open(path_ + ".tmp", std::ios::binary | std::ios::trunc);
  if (!out_) throw Error("cannot write " + path_ + ": cannot create file");
  const std::string text = header(0);
  out_.write(text.data(), static_cast<std::streamsize>(text.size()));
}

PlyWriter::~PlyWriter() {
  if (closed_) return;
  out_.close();
  std::error_code ec;
  std::filesystem::remove(path_ + ".tmp", ec);
}

void PlyWriter::append(const PointBatch& batch) {
  if (batch.hasColor() && batch.colors.size() != batch.points.size()) {
    throw Error("PLY " + path_ + ": batch has " + std::to_string(batch.points.size()) + " points but " +
                std::to_string(batch.colors.size()) + " colours");
  }
  buffer_.resize(batch.size() * kBytesPerPoint);
  for (size_t i = 0; i < batch.size(); ++i) {
    packPoint(buffer_.data() + i * kBytesPerPoint, batch.points[i], batch.hasColor() ? batch.colors[i] : kGrey);
  }
  out_.write(buffer_.data(), static_cast<std::streamsize>(buffer_.size()));
  if (!out_) throw Error("cannot write " + path_ + ": write failed (disk full?)");
  count_ += batch.size();
}

void PlyWriter::close() {
  if (closed_) return;
  const std::string text = header(count_);
  out_.seekp(0);
  out_.write(text.data(), static_cast<std::streamsize>(text.size()));
  out_.close();
  if (!out_) throw Error("cannot write " + path_ + ": write failed (disk full?)");
  std::error_code ec;
  std::filesystem::rename(path_ + ".tmp", path_, ec);
  if (ec) throw Error("cannot write " + path_ + ": " + ec.message());
  closed_ = true;
}

void writePly(const std::string& path, const std::vector<Eigen::Vector3f>& points,
              const std::vector<std::array<uint8_t, 3>>& colors) {
  PointBatch batch;
  batch.points = points;
  batch.colors = colors;
  if (!colors.empty() && colors.size() != points.size()) {
    throw Error("writePly " + path + ": " + std::to_string(points.size()) + " points but " +
                std::to_string(colors.size()) + " colours");
  }
  PlyWriter writer(path);
  writer.append(batch);
  writer.close();
}

PlyPoints readPly(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error("cannot read " + path + ": " + (std::filesystem::exists(path) ? "permission denied" : "no such file"));
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
  const std::vector<std::string> expected = {"float x",     "float y",       "float z",
                                             "uchar red",   "uchar green",   "uchar blue"};
  if (!binary_le || count < 0 || properties != expected) {
    throw Error(path + ": PLY layout is not 'float x y z, uchar red green blue' binary little-endian vertices");
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

}  // namespace cenote::pipeline
