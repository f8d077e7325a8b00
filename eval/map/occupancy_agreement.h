// occupancy_agreement.h: how far two occupancy maps agree, voxel by voxel, from the 3 x 3 table of
// their states (unknown, free, occupied). The map tests compare ours with OctoMap the same way.
//   agreement        = same state / voxels known in either map (unknown vs known counts as a miss)
//   known_agreement  = same state / voxels known in both maps
//   occupied_iou     = occupied in both / occupied in either
//   occupied_precision = occupied in both / occupied in the estimate; occupied_recall: / in the reference
//   agreement_within_voxel = voxels known in either map whose state in each map is found within one
//     voxel (its 3 x 3 x 3 neighbourhood, unknown included) in the other / voxels known in either:
//     a difference that moving a surface or the edge of the seen volume by one voxel explains is not
//     counted. Where the depth noise is as large as a voxel (stereo at a few pixels of disparity),
//     any change of the pixels re-draws which voxels of a surface's shell are hit; the strict numbers
//     measure that noise, this one whether the maps show the same surfaces and free space.
// Fractions in [0, 1]; a ratio of zero voxels is NaN (null in JSON).
// This file is plain data: reading maps lives in map_comparison.h (target cenote_eval_map, which
// links mapping/); cenote_eval itself never depends on mapping/.
// Threads: free functions, independent.
#pragma once

#include <array>
#include <cstdint>
#include <string>

namespace cenote::eval {

// Same order and values as mapping::VoxelState.
enum class Occupancy : uint8_t { kUnknown = 0, kFree = 1, kOccupied = 2 };

struct OccupancyConfusion {
  std::array<std::array<int64_t, 3>, 3> counts{};  // [estimate state][reference state]
  int64_t within_voxel = 0;                        // voxels known in either map whose states agree within one voxel (above)
  void add(Occupancy estimate, Occupancy reference) { ++counts[static_cast<int>(estimate)][static_cast<int>(reference)]; }
  int64_t at(Occupancy estimate, Occupancy reference) const {
    return counts[static_cast<int>(estimate)][static_cast<int>(reference)];
  }
};

struct OccupancyAgreement {
  int64_t known_either = 0, known_both = 0;
  int64_t occupied_estimate = 0, occupied_reference = 0;
  double agreement = 0.0, known_agreement = 0.0;
  double occupied_iou = 0.0, occupied_precision = 0.0, occupied_recall = 0.0;
  double agreement_within_voxel = 0.0;
};

// The unknown/unknown cell is ignored (such voxels are never enumerated).
OccupancyAgreement summarizeAgreement(const OccupancyConfusion& confusion);

// JSON document (kind "map"): the numbers above under agreement, known_agreement, occupied_iou,
// occupied_precision, occupied_recall, agreement_within_voxel, plus the table under "confusion".
std::string toJson(const OccupancyAgreement& a, const OccupancyConfusion& c, const std::string& estimate,
                   const std::string& reference, double voxel_size_m);

}  // namespace cenote::eval
