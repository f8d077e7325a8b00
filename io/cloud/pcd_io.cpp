// pcd_io.cpp: PCD files through PCL's reader and writer, which the plugin libcenote_pcd.so holds
// (pcd_plugin.h); the checks and conversions are here.
#include "io/cloud/pcd_io.h"

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <optional>
#include <utility>

#include "common/error.h"
#include "common/plugin_library.h"
#include "common/scalar_bytes.h"
#include "io/cloud/pcd_plugin.h"

namespace cenote::io {
namespace {

namespace fs = std::filesystem;

using detail::PcdCloud;
using detail::PcdField;

PluginLibrary& plugin() {
  static PluginLibrary library(CENOTE_PCD_PLUGIN_PATH, "libcenote_pcd.so");
  return library;
}

// PCL's reader on `path`: its status; a PCL exception is rethrown as "cannot read PATH as PCD: ...".
int readWithPcl(const std::string& path, bool header_only, PcdCloud& cloud) {
  static const detail::PcdReadFn read = plugin().function<detail::PcdReadFn>("cenote_pcd_read");
  std::string error;
  const int status = read(path.c_str(), header_only, &cloud, &error);
  if (status == detail::kPcdThrew) throw Error("cannot read " + path + " as PCD: " + error);
  return status;
}

// The scalar type of a PCD datatype; nullopt for one we do not read.
std::optional<ScalarType> scalarTypeOf(uint8_t datatype) {
  constexpr std::pair<uint8_t, ScalarType> kTypes[] = {
      {detail::pcd_type::kInt8, ScalarType::kInt8},       {detail::pcd_type::kUint8, ScalarType::kUint8},
      {detail::pcd_type::kInt16, ScalarType::kInt16},     {detail::pcd_type::kUint16, ScalarType::kUint16},
      {detail::pcd_type::kInt32, ScalarType::kInt32},     {detail::pcd_type::kUint32, ScalarType::kUint32},
      {detail::pcd_type::kFloat32, ScalarType::kFloat32}, {detail::pcd_type::kFloat64, ScalarType::kFloat64}};
  for (const auto& [pcl_type, type] : kTypes) {
    if (pcl_type == datatype) return type;
  }
  return std::nullopt;
}

// One scalar of a PCD field as a double; false for a type we do not read.
bool decodePclScalar(const uint8_t* src, uint8_t datatype, double& value) {
  const std::optional<ScalarType> type = scalarTypeOf(datatype);
  if (type) value = decodeScalar(src, *type);
  return type.has_value();
}

const PcdField* findField(const PcdCloud& cloud, const std::string& name) {
  for (const PcdField& f : cloud.fields) {
    if (f.name == name) return &f;
  }
  return nullptr;
}

}  // namespace

void writePcd(const std::string& path, const std::vector<Eigen::Vector3f>& points,
              const std::vector<std::array<uint8_t, 3>>& colors, PcdEncoding encoding) {
  if (!colors.empty() && colors.size() != points.size()) {
    throw Error("cannot write " + path + ": " + std::to_string(points.size()) + " points but " +
                std::to_string(colors.size()) + " colours");
  }
  const std::string temp = path + ".tmp." + std::to_string(::getpid());
  static const detail::PcdWriteFn write = plugin().function<detail::PcdWriteFn>("cenote_pcd_write");
  std::string error;
  const int status = write(temp.c_str(), points.empty() ? nullptr : points.front().data(),
                           colors.empty() ? nullptr : colors.front().data(), points.size(), static_cast<int>(encoding),
                           &error);
  if (status != 0) {
    std::remove(temp.c_str());
    throw Error("cannot write " + path + ": " +
                (status == detail::kPcdThrew ? error : "pcl::PCDWriter returned " + std::to_string(status)));
  }
  std::error_code ec;
  fs::rename(temp, path, ec);
  if (ec) {
    std::remove(temp.c_str());
    throw Error("cannot write " + path + ": " + ec.message());
  }
}

PcdPoints readPcd(const std::string& path) {
  if (!fs::exists(path)) throw Error("cannot read " + path + ": no such file");
  PcdCloud cloud;
  // The header first: PCL 1.13's read() crashes on a file without FIELDS (e.g. not a PCD at all).
  {
    PcdCloud header;
    const int status = readWithPcl(path, true, header);
    if (status < 0 || header.fields.empty()) {
      throw Error("cannot read " + path +
                  " as PCD: pcl::PCDReader finds no PCD header (FIELDS, SIZE, TYPE, WIDTH, "
                  "POINTS, DATA)");
    }
    if (!findField(header, "x") || !findField(header, "y") || !findField(header, "z")) {
      throw Error(path + ": PCD FIELDS has no x, y and z");
    }
    if (static_cast<size_t>(header.width) * header.height == 0) return PcdPoints{};
  }
  const int status = readWithPcl(path, false, cloud);
  if (status < 0) {
    throw Error("cannot read " + path + " as PCD: pcl::PCDReader failed (" + std::to_string(status) +
                "; its message is printed above): a malformed header, a truncated body or not a PCD file");
  }
  const PcdField* axes[3] = {findField(cloud, "x"), findField(cloud, "y"), findField(cloud, "z")};
  if (!axes[0] || !axes[1] || !axes[2]) throw Error(path + ": PCD FIELDS has no x, y and z");
  const PcdField* rgb = findField(cloud, "rgb");
  if (!rgb) rgb = findField(cloud, "rgba");
  const std::optional<ScalarType> rgb_type = rgb ? scalarTypeOf(rgb->datatype) : std::nullopt;
  if (rgb && (!rgb_type || sizeOf(*rgb_type) != 4)) {
    throw Error(path + ": PCD field " + rgb->name + " must be 4 bytes (packed 0x00RRGGBB)");
  }
  const size_t n = static_cast<size_t>(cloud.width) * cloud.height;
  if (cloud.data.size() < n * cloud.point_step) {
    throw Error(path + ": PCD data holds " + std::to_string(cloud.data.size()) + " bytes, " + std::to_string(n) +
                " points need " + std::to_string(n * cloud.point_step));
  }
  PcdPoints out;
  out.points.reserve(n);
  if (rgb) out.colors.reserve(n);
  for (size_t row = 0; row < cloud.height; ++row) {
    for (size_t col = 0; col < cloud.width; ++col) {
      const uint8_t* point = cloud.data.data() + row * cloud.row_step + col * cloud.point_step;
      double xyz[3];
      for (int a = 0; a < 3; ++a) {
        if (!decodePclScalar(point + axes[a]->offset, axes[a]->datatype, xyz[a])) {
          throw Error(path + ": PCD field " + axes[a]->name + " has a type we do not read (PCL datatype " +
                      std::to_string(axes[a]->datatype) + ")");
        }
      }
      if (!std::isfinite(xyz[0]) || !std::isfinite(xyz[1]) || !std::isfinite(xyz[2])) {
        ++out.non_finite_dropped;
        continue;
      }
      out.points.emplace_back(static_cast<float>(xyz[0]), static_cast<float>(xyz[1]), static_cast<float>(xyz[2]));
      if (rgb) {
        uint32_t packed;
        std::memcpy(&packed, point + rgb->offset, 4);
        out.colors.push_back(
            {static_cast<uint8_t>(packed >> 16), static_cast<uint8_t>(packed >> 8), static_cast<uint8_t>(packed)});
      }
    }
  }
  return out;
}

}  // namespace cenote::io
