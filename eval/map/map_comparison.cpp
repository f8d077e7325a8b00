#include "eval/map/map_comparison.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <tuple>
#include <vector>

#include "common/error.h"
#include "mapping/io/map_io.h"

namespace cenote::eval {

OccupancyConfusion compareMaps(const mapping::OccupancyMap& estimate, const mapping::OccupancyMap& reference) {
  const double a = estimate.voxelSize(), b = reference.voxelSize();
  if (std::abs(a - b) > 1e-9 * std::max(a, b)) {
    std::ostringstream text;
    text << "maps of different voxel sizes cannot be compared voxel by voxel: " << a << " m against " << b << " m";
    throw Error(text.str());
  }
  const auto est = estimate.constAccessor();
  const auto ref = reference.constAccessor();
  std::vector<mapping::BlockIndex> blocks = est.knownBlocks();
  const std::vector<mapping::BlockIndex> more = ref.knownBlocks();
  blocks.insert(blocks.end(), more.begin(), more.end());
  const auto key = [](const mapping::BlockIndex& i) { return std::make_tuple(i.x(), i.y(), i.z()); };
  std::sort(blocks.begin(), blocks.end(), [&](const auto& l, const auto& r) { return key(l) < key(r); });
  blocks.erase(std::unique(blocks.begin(), blocks.end()), blocks.end());
  OccupancyConfusion confusion;
  for (const mapping::BlockIndex& block : blocks) {
    for (int offset = 0; offset < mapping::kBlockVoxels; ++offset) {
      const mapping::VoxelIndex ijk = mapping::voxelOfOffset(block, offset);
      const auto e = static_cast<Occupancy>(est.state(ijk));
      const auto r = static_cast<Occupancy>(ref.state(ijk));
      if (e == Occupancy::kUnknown && r == Occupancy::kUnknown) continue;
      confusion.add(e, r);
    }
  }
  return confusion;
}

MapComparison compareMapFiles(const std::string& estimate_path, const std::string& reference_path) {
  const auto load = [](const std::string& path) {
    try {
      return mapping::loadMap(path);
    } catch (const Error& e) {
      const std::string text = e.what();
      throw Error(text.find(path) == std::string::npos ? path + ": " + text : text);
    }
  };
  const auto estimate = load(estimate_path);
  const auto reference = load(reference_path);
  MapComparison result;
  try {
    result.confusion = compareMaps(*estimate, *reference);
  } catch (const Error& e) {
    throw Error(estimate_path + " and " + reference_path + ": " + e.what());
  }
  result.agreement = summarizeAgreement(result.confusion);
  result.voxel_size_m = estimate->voxelSize();
  return result;
}

}  // namespace cenote::eval
