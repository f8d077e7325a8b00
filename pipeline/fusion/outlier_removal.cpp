// outlier_removal.cpp: with pcd_io.cpp, the only files of the pipeline that see PCL's headers.
#include "pipeline/fusion/outlier_removal.h"

#include <pcl/filters/statistical_outlier_removal.h>
#include <pcl/point_types.h>

#include <string>

#include "common/error.h"

namespace cenote::pipeline {

PointBatch removeStatisticalOutliers(const PointBatch& batch, int neighbours, double stddev_mul) {
  if (neighbours < 1) throw Error("outlier removal: neighbours = " + std::to_string(neighbours) + ": must be >= 1");
  if (!(stddev_mul > 0.0)) throw Error("outlier removal: stddev_mul = " + std::to_string(stddev_mul) + ": must be > 0");
  if (batch.size() <= static_cast<size_t>(neighbours)) return batch;
  auto cloud = std::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
  cloud->reserve(batch.size());
  for (const Eigen::Vector3f& p : batch.points) cloud->push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));
  pcl::StatisticalOutlierRemoval<pcl::PointXYZ> filter;
  filter.setInputCloud(cloud);
  filter.setMeanK(neighbours);
  filter.setStddevMulThresh(stddev_mul);
  pcl::Indices kept;
  filter.filter(kept);
  PointBatch out;
  out.t_s = batch.t_s;
  out.origin = batch.origin;
  out.points.reserve(kept.size());
  if (batch.hasColor()) out.colors.reserve(kept.size());
  for (const auto i : kept) {
    out.points.push_back(batch.points[i]);
    if (batch.hasColor()) out.colors.push_back(batch.colors[i]);
  }
  return out;
}

}  // namespace cenote::pipeline
