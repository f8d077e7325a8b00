// map_comparison.h: the occupancy agreement (occupancy_agreement.h) of two maps of mapping/, in
// memory or from .vdb / .bt / .ot files. Part of target cenote_eval_map, built only when mapping/
// is in the build; cenote_eval itself does not depend on mapping/.
// Units: metres; both maps must have the same voxel size (grids are then aligned by construction).
// Threads: takes a ConstAccessor of each map for the whole comparison (integration waits).
#pragma once

#include <string>

#include "eval/map/occupancy_agreement.h"
#include "mapping/occupancy_map.h"

namespace cenote::eval {

// Every voxel known in either map, counted by its pair of states and by whether the states agree
// within one voxel (occupancy_agreement.h).
// @throws cenote::Error when the voxel sizes differ.
OccupancyConfusion compareMaps(const mapping::OccupancyMap& estimate, const mapping::OccupancyMap& reference);

struct MapComparison {
  OccupancyConfusion confusion;
  OccupancyAgreement agreement;
  double voxel_size_m = 0.0;
};

// Loads both files (mapping::loadMap) and compares them.
// @throws cenote::Error naming the file for a missing or foreign map, or both for differing voxel sizes.
MapComparison compareMapFiles(const std::string& estimate_path, const std::string& reference_path);

}  // namespace cenote::eval
