// map_query.h: what planners ask of the occupancy map: voxel states and probabilities at points,
// box counts, segment and capsule collision (with stop-at-unknown), raycasts. All batched.
// Work: box, segment and ray batches have a budget of voxels, counted before any is visited, and
// run in slices: the map's shared lock (one ConstAccessor) is held for one slice of items at a
// time, so integration and other readers get in between two slices, and a caller's check (deadline,
// cancellation) runs there. Each item is answered from one consistent state of the map; the items
// of one batch may see different states when the map changes meanwhile.
// Units: metres, world frame. A voxel belongs to a box / capsule when its centre does.
// Range: boxes, segments and capsules must lie within the map's range, +-mapRange_m on each axis
// (map_range.h: beyond it no voxel is ever known, and voxel indices would overflow).
// Threads: free functions; call them from any number of threads while the map integrates.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "mapping/map_range.h"
#include "mapping/occupancy_map.h"

namespace cenote::mapping {

double mapRange_m(const OccupancyMap& map);                       // mapRange_m(map.voxelSize())
bool withinMapRange(const Aabb& box_m, const OccupancyMap& map);  // voxelsOfBox(...).within_range
std::string mapRangeText(const OccupancyMap& map);                // mapRangeText(map.voxelSize())

// Voxels of work in one slice: a writer waits for at most one slice of a batch reader (or one item,
// when a single item is larger).
inline constexpr uint64_t kSliceVoxels = 1 << 14;

// How a batch of boxes, segments or rays runs.
struct BatchControl {
  // Voxels the batch may visit at most, counted before any is: a segment the voxels its walk can
  // pass (|di| + |dj| + |dk| + 1 between its end voxels), a capsule those of its slabs'
  // cross-sections (at most its bounding box's), a box its voxels. Beyond: ResourceExhaustedError
  // naming `budget_name` (e.g. "server.limits.max_query_voxels"), before the map is read.
  uint64_t max_voxels = std::numeric_limits<uint64_t>::max();
  std::string budget_name = "the query budget";
  // A slice: items until their voxels reach this many (at least one item).
  uint64_t slice_voxels = kSliceVoxels;
  // Called before every slice but the first, without the lock, with the number of items answered
  // so far; it may throw to end the batch (the exception leaves the call). Empty: never called.
  std::function<void(size_t items_done)> between_slices;
};

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
// 2^31 voxels; ResourceExhaustedError beyond control.max_voxels; whatever between_slices throws.
std::vector<BoxCounts> queryBoxes(const OccupancyMap& map, const std::vector<Aabb>& boxes_m,
                                  const BatchControl& control = {});

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
// reaching beyond the map's range, or a capsule whose bounding box holds more than 2^31 voxels;
// ResourceExhaustedError beyond control.max_voxels; whatever control.between_slices throws.
std::vector<CollisionResult> checkSegments(const OccupancyMap& map, const std::vector<SegmentQuery>& segments,
                                           bool stop_at_unknown, const BatchControl& control = {});

struct Ray {
  Eigen::Vector3d origin_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d direction = Eigen::Vector3d::UnitX();  // any length > 0
};

// First occupied voxel along each ray within max_range_m (a segment check of that length, ending
// where the ray leaves the map's range if sooner).
// @throws Error for a zero or non-finite direction, an origin beyond the map's range, or
// max_range_m <= 0; as checkSegments for the budget and slices (each ray's segment counts).
std::vector<CollisionResult> raycast(const OccupancyMap& map, const std::vector<Ray>& rays, double max_range_m,
                                     bool stop_at_unknown, const BatchControl& control = {});

// Voxels a segment or capsule can visit (BatchControl::max_voxels). The segment must be finite and
// within the map's range.
uint64_t visitBound(const SegmentQuery& segment, double voxel_size_m);

}  // namespace cenote::mapping
