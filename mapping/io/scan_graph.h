// scan_graph.h: OctoMap's ScanGraph files (.graph: point clouds in the sensor frame with a 6-DoF
// pose each), the input of OctoMap's graph2tree, turned into world-frame PointBatches the way
// graph2tree does it: points p_world = pose * p_sensor, ray origin = the pose's translation.
// Units: metres. Threads: plain functions.
#pragma once

#include <functional>
#include <string>

#include "common/point_batch.h"

namespace cenote::mapping {

// Calls visit for each scan in file order, at most max_scans (<= 0: all); returns the number of
// scans visited. Empty scans are skipped (and not counted).
// @throws Error when the file is missing or not a ScanGraph.
int readScanGraph(const std::string& path, int max_scans, const std::function<void(const PointBatch&)>& visit);

}  // namespace cenote::mapping
