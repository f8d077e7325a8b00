#include "eval/cloud/voxel_downsample.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>

#include "common/error.h"

namespace cenote::eval {

std::vector<Eigen::Vector3f> voxelDownsample(const std::vector<Eigen::Vector3f>& points, double voxel_m) {
  if (!(voxel_m >= 0.0) || !std::isfinite(voxel_m)) {
    std::ostringstream text;
    text << "voxel size " << voxel_m << " m: must be finite and >= 0 (0 = no downsampling)";
    throw Error(text.str());
  }
  if (voxel_m == 0.0 || points.empty()) return points;
  constexpr double kMaxIndex = 9.0e18;
  struct Keyed {
    std::array<int64_t, 3> key;
    uint32_t index;
  };
  std::vector<Keyed> keyed(points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    for (int a = 0; a < 3; ++a) {
      const double k = std::floor(static_cast<double>(points[i][a]) / voxel_m);
      if (std::abs(k) > kMaxIndex) {
        std::ostringstream text;
        text << "voxel size " << voxel_m << " m is too small for coordinate " << points[i][a];
        throw Error(text.str());
      }
      keyed[i].key[a] = static_cast<int64_t>(k);
    }
    keyed[i].index = static_cast<uint32_t>(i);
  }
  std::sort(keyed.begin(), keyed.end(),
            [](const Keyed& a, const Keyed& b) { return a.key != b.key ? a.key < b.key : a.index < b.index; });
  std::vector<Eigen::Vector3f> result;
  for (size_t begin = 0; begin < keyed.size();) {
    size_t end = begin;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    while (end < keyed.size() && keyed[end].key == keyed[begin].key) {
      sum += points[keyed[end].index].cast<double>();
      ++end;
    }
    result.push_back((sum / static_cast<double>(end - begin)).cast<float>());
    begin = end;
  }
  return result;
}

}  // namespace cenote::eval
