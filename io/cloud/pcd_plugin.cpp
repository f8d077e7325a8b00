// pcd_plugin.cpp: libcenote_pcd.so (pcd_plugin.h), the one file that sees PCL's I/O headers.
#include "io/cloud/pcd_plugin.h"

#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>

#include <cerrno>
#include <cstring>
#include <exception>
#include <fstream>

namespace {

using cenote::io::detail::kPcdThrew;
using cenote::io::detail::PcdCloud;

static_assert(pcl::PCLPointField::INT8 == cenote::io::detail::pcd_type::kInt8 &&
              pcl::PCLPointField::FLOAT64 == cenote::io::detail::pcd_type::kFloat64);

void moveCloud(pcl::PCLPointCloud2&& in, PcdCloud& out) {
  out.fields.clear();
  for (const pcl::PCLPointField& f : in.fields) out.fields.push_back({f.name, f.offset, f.count, f.datatype});
  out.width = in.width;
  out.height = in.height;
  out.point_step = in.point_step;
  out.row_step = in.row_step;
  out.data = std::move(in.data);
}

template <typename Cloud>
int writeCloud(const char* path, const Cloud& cloud, int encoding) {
  using PointT = typename Cloud::PointType;
  if (cloud.empty()) {
    // PCL's writers refuse an empty cloud; its own header with no data is a valid PCD of 0 points.
    std::ofstream out(path, std::ios::binary);
    out << pcl::PCDWriter::generateHeader<PointT>(cloud, 0) << "DATA ascii\n";
    out.flush();
    if (!out) throw std::runtime_error(std::strerror(errno));
    return 0;
  }
  pcl::PCDWriter writer;
  switch (encoding) {
    case 0: return writer.writeASCII(path, cloud, 9);  // 9 digits: floats exactly
    case 1: return writer.writeBinary(path, cloud);
    default: return writer.writeBinaryCompressed(path, cloud);
  }
}

}  // namespace

extern "C" {

__attribute__((visibility("default"))) int cenote_pcd_read(const char* path, bool header_only, PcdCloud* cloud,
                                                           std::string* error) {
  try {
    pcl::PCDReader reader;
    pcl::PCLPointCloud2 read;
    int status = 0;
    if (header_only) {
      Eigen::Vector4f origin;
      Eigen::Quaternionf orientation;
      int version = 0, data_type = 0;
      unsigned int data_index = 0;
      status = reader.readHeader(path, read, origin, orientation, version, data_type, data_index);
    } else {
      status = reader.read(path, read);
    }
    moveCloud(std::move(read), *cloud);
    return status;
  } catch (const std::exception& e) {
    *error = e.what();
    return kPcdThrew;
  }
}

__attribute__((visibility("default"))) int cenote_pcd_write(const char* path, const float* xyz, const uint8_t* rgb,
                                                            std::size_t n, int encoding, std::string* error) {
  try {
    if (!rgb) {
      pcl::PointCloud<pcl::PointXYZ> cloud;
      cloud.reserve(n);
      for (std::size_t i = 0; i < n; ++i) cloud.push_back(pcl::PointXYZ(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]));
      return writeCloud(path, cloud, encoding);
    }
    pcl::PointCloud<pcl::PointXYZRGB> cloud;
    cloud.reserve(n);
    for (std::size_t i = 0; i < n; ++i) {
      pcl::PointXYZRGB q(rgb[3 * i], rgb[3 * i + 1], rgb[3 * i + 2]);
      q.x = xyz[3 * i];
      q.y = xyz[3 * i + 1];
      q.z = xyz[3 * i + 2];
      cloud.push_back(q);
    }
    return writeCloud(path, cloud, encoding);
  } catch (const std::exception& e) {
    *error = e.what();
    return kPcdThrew;
  }
}
}
