// pcd_plugin.h: the C interface of libcenote_pcd.so (pcd_plugin.cpp), PCL's PCD reader and writer
// opened on first use (common/plugin_library.h): PCL's io library pulls VTK and GDCM into a
// process, about sixty shared libraries. pcd_io.cpp checks and converts; the plugin only calls PCL.
// Plain data crosses the boundary (one libstdc++ in the process); exceptions do not: a PCL error
// comes back as its message.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace cenote::io::detail {

// PCL's PCLPointField datatypes (pcl/PCLPointField.h), the same numbers.
namespace pcd_type {
enum : uint8_t { kInt8 = 1, kUint8, kInt16, kUint16, kInt32, kUint32, kFloat32, kFloat64 };
}  // namespace pcd_type

// A pcl::PCLPointField: `count` scalars of `datatype` at byte `offset` of each point.
struct PcdField {
  std::string name;
  uint32_t offset = 0, count = 0;
  uint8_t datatype = 0;
};

// A pcl::PCLPointCloud2, as plain data.
struct PcdCloud {
  std::vector<PcdField> fields;
  uint32_t width = 0, height = 0, point_step = 0, row_step = 0;
  std::vector<uint8_t> data;
};

// What PCL's calls returned: its status, or kPcdThrew with the exception's message.
constexpr int kPcdThrew = -100000;

// The plugin's functions (extern "C" in pcd_plugin.cpp).
// pcl::PCDReader::readHeader (header_only) or read into *cloud; returns PCL's status or kPcdThrew.
using PcdReadFn = int (*)(const char* path, bool header_only, PcdCloud* cloud, std::string* error);
// Writes n points (xyz: 3 floats each; rgb: 3 bytes each, or null) to `path` with encoding 0 ascii,
// 1 binary, 2 binary compressed; returns PCL's status or kPcdThrew.
using PcdWriteFn = int (*)(const char* path, const float* xyz, const uint8_t* rgb, std::size_t n, int encoding,
                           std::string* error);

}  // namespace cenote::io::detail
