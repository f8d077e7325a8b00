// pcd_io.cpp: the one file of io/ that sees PCL's I/O headers (pcd_io.h).
#include "io/cloud/pcd_io.h"

#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <utility>

#include "common/error.h"
#include "common/scalar_bytes.h"

namespace cenote::io {
namespace {

namespace fs = std::filesystem;

// One scalar of a PCLPointCloud2 field as a double; false for a type we do not read.
bool decodePclScalar(const uint8_t* src, uint8_t datatype, double& value) {
  constexpr std::pair<uint8_t, ScalarType> kTypes[] = {
      {pcl::PCLPointField::INT8, ScalarType::kInt8},       {pcl::PCLPointField::UINT8, ScalarType::kUint8},
      {pcl::PCLPointField::INT16, ScalarType::kInt16},     {pcl::PCLPointField::UINT16, ScalarType::kUint16},
      {pcl::PCLPointField::INT32, ScalarType::kInt32},     {pcl::PCLPointField::UINT32, ScalarType::kUint32},
      {pcl::PCLPointField::FLOAT32, ScalarType::kFloat32}, {pcl::PCLPointField::FLOAT64, ScalarType::kFloat64}};
  for (const auto& [pcl_type, type] : kTypes) {
    if (pcl_type == datatype) {
      value = decodeScalar(src, type);
      return true;
    }
  }
  return false;
}

const pcl::PCLPointField* findField(const pcl::PCLPointCloud2& cloud, const std::string& name) {
  for (const pcl::PCLPointField& f : cloud.fields) {
    if (f.name == name) return &f;
  }
  return nullptr;
}

template <typename Cloud>
void writeCloud(const std::string& temp, const Cloud& cloud, PcdEncoding encoding) {
  using PointT = typename Cloud::PointType;
  pcl::PCDWriter writer;
  if (cloud.empty()) {
    // PCL's writers refuse an empty cloud; its own header with no data is a valid PCD of 0 points.
    std::ofstream out(temp, std::ios::binary);
    out << pcl::PCDWriter::generateHeader<PointT>(cloud, 0) << "DATA ascii\n";
    out.flush();
    if (!out) throw Error(std::strerror(errno));
    return;
  }
  int status = 0;
  switch (encoding) {
    case PcdEncoding::kAscii: status = writer.writeASCII(temp, cloud, 9); break;  // 9 digits: floats exactly
    case PcdEncoding::kBinary: status = writer.writeBinary(temp, cloud); break;
    case PcdEncoding::kBinaryCompressed: status = writer.writeBinaryCompressed(temp, cloud); break;
  }
  if (status != 0) throw Error("pcl::PCDWriter returned " + std::to_string(status));
}

}  // namespace

void writePcd(const std::string& path, const std::vector<Eigen::Vector3f>& points,
              const std::vector<std::array<uint8_t, 3>>& colors, PcdEncoding encoding) {
  if (!colors.empty() && colors.size() != points.size()) {
    throw Error("cannot write " + path + ": " + std::to_string(points.size()) + " points but " +
                std::to_string(colors.size()) + " colours");
  }
  const std::string temp = path + ".tmp." + std::to_string(::getpid());
  try {
    if (colors.empty()) {
      pcl::PointCloud<pcl::PointXYZ> cloud;
      cloud.reserve(points.size());
      for (const Eigen::Vector3f& p : points) cloud.push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));
      writeCloud(temp, cloud, encoding);
    } else {
      pcl::PointCloud<pcl::PointXYZRGB> cloud;
      cloud.reserve(points.size());
      for (size_t i = 0; i < points.size(); ++i) {
        pcl::PointXYZRGB q(colors[i][0], colors[i][1], colors[i][2]);
        q.x = points[i].x();
        q.y = points[i].y();
        q.z = points[i].z();
        cloud.push_back(q);
      }
      writeCloud(temp, cloud, encoding);
    }
  } catch (const std::exception& e) {
    std::remove(temp.c_str());
    throw Error("cannot write " + path + ": " + e.what());
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
  pcl::PCLPointCloud2 cloud;
  pcl::PCDReader reader;
  int status = 0;
  // The header first: PCL 1.13's read() crashes on a file without FIELDS (e.g. not a PCD at all).
  {
    Eigen::Vector4f origin;
    Eigen::Quaternionf orientation;
    int version = 0, data_type = 0;
    unsigned int data_index = 0;
    pcl::PCLPointCloud2 header;
    try {
      status = reader.readHeader(path, header, origin, orientation, version, data_type, data_index);
    } catch (const std::exception& e) {
      throw Error("cannot read " + path + " as PCD: " + e.what());
    }
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
  try {
    status = reader.read(path, cloud);
  } catch (const std::exception& e) {
    throw Error("cannot read " + path + " as PCD: " + e.what());
  }
  if (status < 0) {
    throw Error("cannot read " + path + " as PCD: pcl::PCDReader failed (" + std::to_string(status) +
                "; its message is printed above): a malformed header, a truncated body or not a PCD file");
  }
  const pcl::PCLPointField* axes[3] = {findField(cloud, "x"), findField(cloud, "y"), findField(cloud, "z")};
  if (!axes[0] || !axes[1] || !axes[2]) throw Error(path + ": PCD FIELDS has no x, y and z");
  const pcl::PCLPointField* rgb = findField(cloud, "rgb");
  if (!rgb) rgb = findField(cloud, "rgba");
  if (rgb && pcl::getFieldSize(rgb->datatype) != 4) {
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
