// map_query.h: what planners ask of the occupancy map: voxel states and probabilities at points,
// box counts, segment and capsule collision (with stop-at-unknown), raycasts. All batched: each
// call takes one ConstAccessor (one shared lock) for the whole batch.
// Units: metres, world frame. A voxel belongs to a box / capsule when its centre does.
// Range: boxes, segments and capsules must lie within the map's range, +-mapRange_m(map) on each
// axis (voxel_types.h: beyond it no voxel is ever known, and voxel indices would overflow).
// Threads: free functions; call them from any number of threads while the map integrates (each
// call holds the map's shared lock for its duration; see occupancy_map.h).
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "mapping/occupancy_map.h"

namespace cenote::mapping {

// Half the side of the cube, centred on the origin, that holds every voxel the map can know.
double mapRange_m(const OccupancyMap& map);
// Whether `box_m` lies within that cube (an empty box does).
bool withinMapRange(const Aabb& box_m, const OccupancyMap& map);
// "the map's range, +-N m on each axis", for error messages.
std::string mapRangeText(const OccupancyMap& map);

struct VoxelQuery {
  VoxelState state = VoxelState::kUnknown;
  double probability = 0.5;  // 0.5 when unknown
};

// State and probability of the voxel holding each point. A non-finite point reports unknown.
std::vector<VoxelQuery> queryVoxels(const OccupancyMap& map, const std::vector<Eigen::Vector3d>& points_m);

struct BoxCounts {
  uint64_t unknown = 0;
  uint64_t free = 0;
  uint64_t occupied = 0;
  bool anyOccupied() const { return occupied > 0; }
  uint64_t total() const { return unknown + free + occupied; }
};

// Counts of the voxels whose centre lies in each box. An empty box counts nothing.
// @throws Error for a non-finite box, one reaching beyond the map's range or holding more than
// 2^31 voxels.
std::vector<BoxCounts> queryBoxes(const OccupancyMap& map, const std::vector<Aabb>& boxes_m);

struct SegmentQuery {
  Eigen::Vector3d start_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d end_m = Eigen::Vector3d::Zero();
  double radius_m = 0.0;  // 0: the voxels the segment passes through; > 0: a capsule
};

// The box a segment or capsule can touch: its ends' box grown by its radius.
Aabb boundsOf(const SegmentQuery& segment);

struct CollisionResult {
  bool hit = false;             // an occupied voxel, before any unknown with stop_at_unknown
  double hit_distance_m = 0.0;  // along the segment, from its start to the hit voxel's centre projection
  VoxelIndex hit_voxel = VoxelIndex::Zero();
  bool crossed_unknown = false;     // some unknown voxel lies before the hit (or anywhere when no hit)
  double unknown_distance_m = 0.0;  // of the first unknown voxel, when crossed_unknown
  bool stopped_at_unknown = false;  // stop_at_unknown and an unknown voxel came first: not free to pass
  // Safe to travel: no occupied voxel and, with stop_at_unknown, no unknown one.
  bool isClear() const { return !hit && !stopped_at_unknown; }
};

// First occupied voxel along each segment or capsule, in order of distance from its start.
// stop_at_unknown: the walk ends at the first unknown voxel (stopped_at_unknown), since unknown is
// never free. @throws Error for a non-finite segment, a negative radius, a segment or capsule
// reaching beyond the map's range, or a capsule whose bounding box holds more than 2^31 voxels.
std::vector<CollisionResult> checkSegments(const OccupancyMap& map, const std::vector<SegmentQuery>& segments,
                                           bool stop_at_unknown);

struct Ray {
  Eigen::Vector3d origin_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d direction = Eigen::Vector3d::UnitX();  // any length > 0
};

// First occupied voxel along each ray within max_range_m (a segment check of that length, ending
// where the ray leaves the map's range if sooner).
// @throws Error for a zero or non-finite direction, an origin beyond the map's range, or
// max_range_m <= 0.
std::vector<CollisionResult> raycast(const OccupancyMap& map, const std::vector<Ray>& rays, double max_range_m,
                                     bool stop_at_unknown);

}  // namespace cenote::mapping
