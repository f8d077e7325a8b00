// outlier_removal.h: PCL's statistical outlier removal (pcl::StatisticalOutlierRemoval) on a batch
// of fused points, an optional last filter of the runner's output (run.outlier_neighbours).
// For each point the mean distance d_i to its k nearest neighbours in the batch is computed; a
// point is kept when d_i <= mean(d) + stddev_mul * stddev(d) over the batch (R. B. Rusu et al.,
// "Towards 3D Point Cloud Based Object Maps for Household Environments", RAS 56(11), 2008).
// Units: metres (any frame: distances only). Deterministic: the same batch gives the same points
// in the same order (a single-threaded k-d tree), whatever ran before.
// PCL's headers are seen by outlier_removal.cpp alone. Threads: a free function, independent.
#pragma once

#include "common/point_batch.h"

namespace cenote::pipeline {

// @param neighbours k, >= 1. @param stddev_mul the threshold in standard deviations, > 0.
// @return the kept points with their colours, in their order; t_s and origin copied. A batch of
//         at most k points is returned unchanged (too few neighbours to judge).
// @throws cenote::Error for neighbours < 1 or stddev_mul <= 0.
PointBatch removeStatisticalOutliers(const PointBatch& batch, int neighbours, double stddev_mul);

}  // namespace cenote::pipeline
