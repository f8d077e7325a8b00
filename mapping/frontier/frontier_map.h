// frontier_map.h: exploration frontiers of the occupancy map: free voxels with an unknown
// 6-neighbour, grouped into 26-connected clusters, large clusters split along their main axis
// (PCA) until no side of their bounding box exceeds MapConfig::frontier_max_extent_m, clusters
// smaller than MapConfig::frontier_min_voxels dropped.
// Incremental: update(delta) re-examines only the changed blocks whose voxel states (known,
// occupied) changed, not just their log-odds, and those of their 6 face neighbours whose facing
// layer of known voxels changed, with 512-bit masks per block (frontier = free and not known in
// some face direction, by 64-bit word shifts); the masks of a block some delta named come from
// the snapshot this map keeps of it (so give it every delta), those of other blocks from the map.
// Each block's frontier is cut into 26-connected pieces by bit-parallel dilation
// (frontier/frontier_bits.h); pieces of neighbouring blocks are joined by a union-find on their
// facing layers. Only the components whose voxels or faces changed, and those they now touch, are
// re-labelled and re-split (frontier/cluster_split.h, exact integer moments kept per piece: the
// clusters depend only on the map, not on the order or grouping of updates); other clusters keep
// their ids.
// Units: metres, world frame.
// Threads: update() for one writer; clusters() from any thread (a shared lock).
#pragma once

#include <Eigen/Core>
#include <memory>
#include <optional>
#include <shared_mutex>
#include <vector>

#include "mapping/detail/fair_shared_mutex.h"
#include "mapping/occupancy_map.h"

namespace cenote::mapping {

struct FrontierCluster {
  uint64_t id = 0;  // stable while the cluster is untouched
  size_t num_voxels = 0;
  Eigen::Vector3d centroid_m = Eigen::Vector3d::Zero();
  Aabb bounds_m;                                        // of the voxels (their faces)
  Eigen::Vector3d direction = Eigen::Vector3d::Zero();  // mean unit direction into the unknown
  double distance_m = 0.0;                              // from the position given to clusters()
};

class FrontierMap {
 public:
  // `map` must outlive the frontier map. With a region of interest, only voxels whose centre lies
  // in it can be frontiers.
  explicit FrontierMap(const OccupancyMap& map, std::optional<Aabb> region_of_interest_m = std::nullopt);
  ~FrontierMap();
  FrontierMap(const FrontierMap&) = delete;
  FrontierMap& operator=(const FrontierMap&) = delete;

  // Give it every delta the map returns, in order.
  void update(const MapDelta& delta);
  // Recomputes from every known block.
  void rebuild();

  // Clusters sorted by distance of their centroid from `position_m`.
  std::vector<FrontierCluster> clusters(const Eigen::Vector3d& position_m) const;
  size_t numFrontierVoxels() const;

 private:
  struct Impl;
  const OccupancyMap& map_;
  std::unique_ptr<Impl> impl_;
  mutable detail::FairSharedMutex mutex_;
};

}  // namespace cenote::mapping
