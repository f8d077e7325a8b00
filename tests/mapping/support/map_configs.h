// map_configs.h: the map settings the mapping tests start from: MapConfig's defaults but for the
// voxel size and the range beyond which a point is no hit (MapConfig::max_range_m).
#pragma once

#include "mapping/map_config.h"

namespace cenote::mapping::test {

inline MapConfig mapConfig(double voxel_size_m, double max_range_m = MapConfig{}.max_range_m) {
  MapConfig config;
  config.voxel_size_m = voxel_size_m;
  config.max_range_m = max_range_m;
  return config;
}

}  // namespace cenote::mapping::test
