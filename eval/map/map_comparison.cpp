#include "eval/map/map_comparison.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <span>
#include <sstream>
#include <tuple>
#include <vector>

#include "common/error.h"
#include "mapping/io/map_io.h"

namespace cenote::eval {

namespace {

// A block and its one-voxel apron: 10 x 10 x 10 voxels, x slowest, the block's voxels at 1..8.
constexpr int kSide = mapping::kBlockSide + 2;
constexpr int kRegionVoxels = kSide * kSide * kSide;
constexpr int at(int x, int y, int z) { return (x * kSide + y) * kSide + z; }

// The states of one block and its apron in a map, and for each voxel the set of states (bit 1 << state)
// within one voxel of it: its 3 x 3 x 3 neighbourhood, OR-ed axis by axis. The sets are exact at the
// block's voxels, which is all the comparison reads.
struct Region {
  std::array<mapping::VoxelState, kRegionVoxels> state{};
  std::array<uint8_t, kRegionVoxels> near{};
};

void readRegion(const mapping::OccupancyMap::ConstAccessor& map, std::span<const mapping::VoxelIndex> ijk, Region& r) {
  map.states(ijk, r.state);
  for (int i = 0; i < kRegionVoxels; ++i) r.near[i] = static_cast<uint8_t>(1u << static_cast<int>(r.state[i]));
  std::array<uint8_t, kRegionVoxels> pass{};
  const int stride[3] = {kSide * kSide, kSide, 1};
  for (int axis = 0; axis < 3; ++axis) {
    for (int x = 0; x < kSide; ++x) {
      for (int y = 0; y < kSide; ++y) {
        for (int z = 0; z < kSide; ++z) {
          const int i = at(x, y, z), c = axis == 0 ? x : axis == 1 ? y : z;
          uint8_t bits = r.near[i];
          if (c > 0) bits |= r.near[i - stride[axis]];
          if (c < kSide - 1) bits |= r.near[i + stride[axis]];
          pass[i] = bits;
        }
      }
    }
    r.near = pass;
  }
}

}  // namespace

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
  std::vector<mapping::VoxelIndex> ijk(kRegionVoxels);
  Region e, r;
  for (const mapping::BlockIndex& block : blocks) {
    const mapping::VoxelIndex origin = block * mapping::kBlockSide - mapping::VoxelIndex::Ones();
    for (int x = 0; x < kSide; ++x) {
      for (int y = 0; y < kSide; ++y) {
        for (int z = 0; z < kSide; ++z) ijk[at(x, y, z)] = origin + mapping::VoxelIndex(x, y, z);
      }
    }
    readRegion(est, ijk, e);
    readRegion(ref, ijk, r);
    for (int x = 1; x <= mapping::kBlockSide; ++x) {  // the block's own voxels, inside the apron
      for (int y = 1; y <= mapping::kBlockSide; ++y) {
        for (int z = 1; z <= mapping::kBlockSide; ++z) {
          const int i = at(x, y, z);
          if (e.state[i] == mapping::VoxelState::kUnknown && r.state[i] == mapping::VoxelState::kUnknown) continue;
          const int se = static_cast<int>(e.state[i]), sr = static_cast<int>(r.state[i]);
          confusion.add(static_cast<Occupancy>(se), static_cast<Occupancy>(sr));
          if ((r.near[i] >> se & 1) && (e.near[i] >> sr & 1)) ++confusion.within_voxel;
        }
      }
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
