// ray_maps.h: small occupancy maps made of a few rays, for the mapping tests that want a map whose
// free and occupied voxels they can name (map ranges, map queries).
#pragma once

#include <memory>
#include <vector>

#include "common/point_batch.h"
#include "mapping/occupancy_map.h"
#include "tests/mapping/support/map_configs.h"

namespace cenote::mapping::test {

// One batch of rays from `origin` to each of `ends` (uncoloured).
inline PointBatch rays(const Eigen::Vector3d& origin, std::vector<Eigen::Vector3f> ends) {
  PointBatch b;
  b.origin = origin;
  b.points = std::move(ends);
  return b;
}

// A map of `voxel_size_m` voxels (the other settings MapConfig's defaults) with `batches`
// integrated one after the other.
inline std::unique_ptr<OccupancyMap> mapOfRays(double voxel_size_m, const std::vector<PointBatch>& batches) {
  auto map = std::make_unique<OccupancyMap>(mapConfig(voxel_size_m));
  for (const PointBatch& b : batches) map->integrate(b);
  return map;
}

}  // namespace cenote::mapping::test
