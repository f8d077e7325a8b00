#include "mapping/map_range.h"

#include <algorithm>
#include <cmath>

#include "common/error.h"

namespace cenote::mapping {

double mapRange_m(double voxel_size_m) { return kMaxVoxelIndex * voxel_size_m; }

std::string mapRangeText(double voxel_size_m) {
  return "the map's range, +-" + std::to_string(static_cast<int64_t>(mapRange_m(voxel_size_m))) + " m on each axis";
}

uint64_t BoxVoxels::count() const {
  if (voxels.isEmpty()) return 0;
  uint64_t n = 1;
  for (int a = 0; a < 3; ++a) n *= static_cast<uint64_t>(int64_t{voxels.max[a]} - voxels.min[a] + 1);
  return n;
}

BoxVoxels voxelsOfBox(const Aabb& box_m, double voxel_size_m, const std::string& what) {
  if (!box_m.min_m.allFinite() || !box_m.max_m.allFinite()) throw Error(what + " must be finite");
  BoxVoxels out;
  if (box_m.isEmpty()) return out;
  const double range = mapRange_m(voxel_size_m);
  out.within_range = (box_m.min_m.array() >= -range).all() && (box_m.max_m.array() <= range).all();
  // Voxel i's centre (i + 0.5) s lies in [min, max] for ceil(min / s - 0.5) <= i <= floor(max / s - 0.5),
  // computed in double and clipped before the conversion to int.
  constexpr double kLimit = kMaxVoxelIndex;
  for (int a = 0; a < 3; ++a) {
    const double lo = std::ceil(box_m.min_m[a] / voxel_size_m - 0.5);
    const double hi = std::floor(box_m.max_m[a] / voxel_size_m - 0.5);
    if (lo > hi || lo > kLimit || hi < -kLimit) return BoxVoxels{VoxelBox{}, out.within_range};
    out.voxels.min[a] = static_cast<int>(std::max(lo, -kLimit));
    out.voxels.max[a] = static_cast<int>(std::min(hi, kLimit));
  }
  return out;
}

}  // namespace cenote::mapping
