// outlier_removal.cpp: PCL's filter through the plugin libcenote_pcl_filters.so (outlier_plugin.cpp).
#include "pipeline/fusion/outlier_removal.h"

#include <string>
#include <vector>

#include "common/error.h"
#include "common/plugin_library.h"

namespace cenote::pipeline {
namespace {

using InliersFn = bool (*)(const float*, std::size_t, int, double, std::vector<int>*, std::string*);

PluginLibrary& plugin() {
  static PluginLibrary library(CENOTE_PCL_FILTERS_PATH, "libcenote_pcl_filters.so");
  return library;
}

}  // namespace

PointBatch removeStatisticalOutliers(const PointBatch& batch, int neighbours, double stddev_mul) {
  if (neighbours < 1) throw Error("outlier removal: neighbours = " + std::to_string(neighbours) + ": must be >= 1");
  if (!(stddev_mul > 0.0)) throw Error("outlier removal: stddev_mul = " + std::to_string(stddev_mul) + ": must be > 0");
  if (batch.size() <= static_cast<size_t>(neighbours)) return batch;
  static const InliersFn inliers = plugin().function<InliersFn>("cenote_statistical_inliers");
  std::vector<int> kept;
  std::string error;
  if (!inliers(batch.points.front().data(), batch.size(), neighbours, stddev_mul, &kept, &error)) {
    throw Error("outlier removal: PCL failed: " + error);
  }
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
