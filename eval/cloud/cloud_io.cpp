#include "eval/cloud/cloud_io.h"

#include <algorithm>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>

#include "common/error.h"
#include "common/scalar_bytes.h"
#include "io/cloud/pcd_io.h"

namespace cenote::eval {
namespace {

namespace fs = std::filesystem;

bool parsePlyType(const std::string& name, ScalarType& t) {
  static const std::pair<const char*, ScalarType> kNames[] = {
      {"char", ScalarType::kInt8},      {"int8", ScalarType::kInt8},       {"uchar", ScalarType::kUint8},
      {"uint8", ScalarType::kUint8},    {"short", ScalarType::kInt16},     {"int16", ScalarType::kInt16},
      {"ushort", ScalarType::kUint16},  {"uint16", ScalarType::kUint16},   {"int", ScalarType::kInt32},
      {"int32", ScalarType::kInt32},    {"uint", ScalarType::kUint32},     {"uint32", ScalarType::kUint32},
      {"float", ScalarType::kFloat32},  {"float32", ScalarType::kFloat32}, {"double", ScalarType::kFloat64},
      {"float64", ScalarType::kFloat64}};
  for (const auto& [n, type] : kNames) {
    if (name == n) {
      t = type;
      return true;
    }
  }
  return false;
}

std::string readAll(std::ifstream& in) {
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

std::ifstream openOrThrow(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    throwReadError(path, "not readable");
  }
  return in;
}

// Whitespace-separated number tokens of an ASCII body.
class TokenReader {
 public:
  TokenReader(const std::string& text, size_t pos) : text_(text), pos_(pos) {}
  bool next(double& value) {
    while (pos_ < text_.size() && std::isspace(static_cast<unsigned char>(text_[pos_]))) ++pos_;
    if (pos_ >= text_.size()) return false;
    size_t end = pos_;
    while (end < text_.size() && !std::isspace(static_cast<unsigned char>(text_[end]))) ++end;
    const std::string token = text_.substr(pos_, end - pos_);
    char* stop = nullptr;
    value = std::strtod(token.c_str(), &stop);
    if (stop == token.c_str() || *stop != '\0') {
      bad_ = token;
      return false;
    }
    pos_ = end;
    return true;
  }
  const std::string& bad() const { return bad_; }

 private:
  const std::string& text_;
  size_t pos_;
  std::string bad_;
};

void addPoint(Cloud& cloud, double x, double y, double z) {
  if (std::isfinite(x) && std::isfinite(y) && std::isfinite(z)) {
    cloud.points.emplace_back(static_cast<float>(x), static_cast<float>(y), static_cast<float>(z));
  } else {
    ++cloud.non_finite_dropped;
  }
}

struct PlyProperty {
  std::string name;
  ScalarType type = ScalarType::kFloat32;
  bool is_list = false;
  ScalarType count_type = ScalarType::kUint8;
};

struct PlyElement {
  std::string name;
  long count = 0;
  std::vector<PlyProperty> properties;
};

}  // namespace

Cloud readPlyCloud(const std::string& path) {
  std::ifstream in = openOrThrow(path);
  const std::string data = readAll(in);
  size_t pos = 0;
  auto nextLine = [&](std::string& line) {
    if (pos >= data.size()) return false;
    size_t end = data.find('\n', pos);
    if (end == std::string::npos) end = data.size();
    line = data.substr(pos, end - pos);
    if (!line.empty() && line.back() == '\r') line.pop_back();
    pos = end + 1;
    return true;
  };
  std::string line;
  if (!nextLine(line) || line != "ply") throw Error(path + ": not a PLY file (first line is not 'ply')");
  std::string format;
  std::vector<PlyElement> elements;
  bool ended = false;
  int line_number = 1;
  while (nextLine(line)) {
    ++line_number;
    const std::string where = path + ": PLY header line " + std::to_string(line_number) + " '" + line + "': ";
    std::istringstream words(line);
    std::string keyword;
    words >> keyword;
    if (keyword == "end_header") {
      ended = true;
      break;
    }
    if (keyword == "format") {
      words >> format;
      if (format != "ascii" && format != "binary_little_endian" && format != "binary_big_endian") {
        throw Error(where + "unknown format (ascii, binary_little_endian or binary_big_endian)");
      }
    } else if (keyword == "element") {
      PlyElement e;
      words >> e.name >> e.count;
      if (!words || e.count < 0) throw Error(where + "expected 'element NAME COUNT'");
      elements.push_back(e);
    } else if (keyword == "property") {
      if (elements.empty()) throw Error(where + "property before any element");
      PlyProperty p;
      std::string type;
      words >> type;
      if (type == "list") {
        std::string count_type, item_type;
        words >> count_type >> item_type >> p.name;
        p.is_list = true;
        if (!parsePlyType(count_type, p.count_type) || !parsePlyType(item_type, p.type)) {
          throw Error(where + "unknown list type");
        }
      } else {
        words >> p.name;
        if (!parsePlyType(type, p.type)) throw Error(where + "unknown property type '" + type + "'");
      }
      if (!words) throw Error(where + "expected 'property TYPE NAME'");
      elements.back().properties.push_back(p);
    } else if (keyword != "comment" && keyword != "obj_info" && !keyword.empty()) {
      throw Error(where + "unexpected header line");
    }
  }
  if (!ended) throw Error(path + ": PLY header has no end_header");
  if (format.empty()) throw Error(path + ": PLY header has no format line");
  const auto vertex = std::find_if(elements.begin(), elements.end(),
                                   [](const PlyElement& e) { return e.name == "vertex"; });
  if (vertex == elements.end()) throw Error(path + ": PLY file has no 'vertex' element");
  int ix = -1, iy = -1, iz = -1;
  for (size_t i = 0; i < vertex->properties.size(); ++i) {
    const std::string& n = vertex->properties[i].name;
    if (vertex->properties[i].is_list) continue;
    if (n == "x") ix = static_cast<int>(i);
    if (n == "y") iy = static_cast<int>(i);
    if (n == "z") iz = static_cast<int>(i);
  }
  if (ix < 0 || iy < 0 || iz < 0) throw Error(path + ": PLY vertex element has no x, y and z properties");

  Cloud cloud;
  // Every vertex takes at least a byte of the file: a header's count is never trusted beyond that.
  cloud.points.reserve(std::min(static_cast<size_t>(vertex->count), data.size() - std::min(pos, data.size())));
  std::vector<double> values;
  if (format == "ascii") {
    TokenReader tokens(data, pos);
    for (auto e = elements.begin(); e != elements.end(); ++e) {
      const bool is_vertex = e == vertex;
      for (long i = 0; i < e->count; ++i) {
        values.assign(e->properties.size(), 0.0);
        for (size_t k = 0; k < e->properties.size(); ++k) {
          double v = 0.0;
          auto fail = [&] {
            throw Error(
                path + ": PLY " + e->name + " " + std::to_string(i) + " of " + std::to_string(e->count) +
                (tokens.bad().empty() ? ": file ends early (truncated)" : ": '" + tokens.bad() + "' is not a number"));
          };
          if (!tokens.next(v)) fail();
          if (e->properties[k].is_list) {
            for (long j = 0; j < static_cast<long>(v); ++j) {
              double item = 0.0;
              if (!tokens.next(item)) fail();
            }
          } else {
            values[k] = v;
          }
        }
        if (is_vertex) addPoint(cloud, values[ix], values[iy], values[iz]);
      }
      if (is_vertex) break;
    }
    return cloud;
  }
  const bool swap = format == "binary_big_endian";
  for (auto e = elements.begin(); e != elements.end(); ++e) {
    const bool is_vertex = e == vertex;
    bool fixed = true;
    size_t record = 0;
    std::vector<size_t> offsets;
    for (const PlyProperty& p : e->properties) {
      offsets.push_back(record);
      fixed = fixed && !p.is_list;
      record += sizeOf(p.type);
    }
    const auto truncated = [&](long i) {
      return Error(path + ": PLY file is truncated in element '" + e->name + "' (" + std::to_string(i) + " of " +
                   std::to_string(e->count) + " read)");
    };
    if (fixed) {
      const size_t left = data.size() - std::min(pos, data.size());
      if (record > 0 && static_cast<size_t>(e->count) > left / record) {
        throw truncated(static_cast<long>(left / record));
      }
      if (is_vertex) {
        const char* base = data.data() + pos;
        for (long i = 0; i < e->count; ++i) {
          const char* r = base + record * i;
          addPoint(cloud, decodeScalar(r + offsets[ix], e->properties[ix].type, swap),
                   decodeScalar(r + offsets[iy], e->properties[iy].type, swap),
                   decodeScalar(r + offsets[iz], e->properties[iz].type, swap));
        }
        break;
      }
      pos += record * static_cast<size_t>(e->count);
      continue;
    }
    for (long i = 0; i < e->count; ++i) {
      values.assign(e->properties.size(), 0.0);
      for (size_t k = 0; k < e->properties.size(); ++k) {
        const PlyProperty& p = e->properties[k];
        if (p.is_list) {
          if (pos + sizeOf(p.count_type) > data.size()) throw truncated(i);
          const auto n = static_cast<long>(decodeScalar(data.data() + pos, p.count_type, swap));
          pos += sizeOf(p.count_type);
          if (n < 0) throw Error(path + ": PLY list of negative length in element '" + e->name + "'");
          if (static_cast<size_t>(n) > (data.size() - pos) / sizeOf(p.type)) throw truncated(i);
          pos += static_cast<size_t>(n) * sizeOf(p.type);
        } else {
          if (pos + sizeOf(p.type) > data.size()) throw truncated(i);
          values[k] = decodeScalar(data.data() + pos, p.type, swap);
          pos += sizeOf(p.type);
        }
      }
      if (is_vertex) addPoint(cloud, values[ix], values[iy], values[iz]);
    }
    if (is_vertex) break;
  }
  return cloud;
}

Cloud readPcdCloud(const std::string& path) {
  io::PcdPoints pcd = io::readPcd(path);
  Cloud cloud;
  cloud.points = std::move(pcd.points);
  cloud.non_finite_dropped = pcd.non_finite_dropped;
  return cloud;
}

Cloud readCloud(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext == ".ply") return readPlyCloud(path);
  if (ext == ".pcd") return readPcdCloud(path);
  std::ifstream in = openOrThrow(path);
  std::string first;
  std::getline(in, first);
  if (first.rfind("ply", 0) == 0) return readPlyCloud(path);
  if (first.rfind("#", 0) == 0 || first.rfind("VERSION", 0) == 0 || first.rfind("FIELDS", 0) == 0)
    return readPcdCloud(path);
  throw Error(path + ": neither a PLY nor a PCD file (by extension and first line)");
}

void writePcdAscii(const std::string& path, const std::vector<Eigen::Vector3f>& points) {
  std::ofstream out(path, std::ios::trunc);
  if (!out) throw Error("cannot write " + path + ": cannot create file");
  out << "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\n"
      << "COUNT 1 1 1\nWIDTH " << points.size() << "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " << points.size()
      << "\nDATA ascii\n";
  out.precision(9);
  for (const Eigen::Vector3f& p : points) out << p.x() << " " << p.y() << " " << p.z() << "\n";
  out.close();
  if (!out) throw Error("cannot write " + path + ": write failed (disk full?)");
}

}  // namespace cenote::eval
