// outlier_plugin.cpp: libcenote_pcl_filters.so, PCL's statistical outlier removal behind a C
// interface, opened on first use by outlier_removal.cpp (common/plugin_library.h): linking PCL's
// filters would load PCL and its dependencies at every start of every program. The one file of
// the pipeline that sees PCL's headers.
#include <pcl/filters/statistical_outlier_removal.h>
#include <pcl/point_types.h>

#include <cstddef>
#include <exception>
#include <string>
#include <vector>

extern "C" {

// The indices of the n points (xyz: 3 floats each) that pcl::StatisticalOutlierRemoval keeps with
// `neighbours` and `stddev_mul`, into *kept; false with *error set when PCL throws.
__attribute__((visibility("default"))) bool cenote_statistical_inliers(const float* xyz, std::size_t n, int neighbours,
                                                                       double stddev_mul, std::vector<int>* kept,
                                                                       std::string* error) {
  try {
    auto cloud = std::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
    cloud->reserve(n);
    for (std::size_t i = 0; i < n; ++i) cloud->push_back(pcl::PointXYZ(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]));
    pcl::StatisticalOutlierRemoval<pcl::PointXYZ> filter;
    filter.setInputCloud(cloud);
    filter.setMeanK(neighbours);
    filter.setStddevMulThresh(stddev_mul);
    pcl::Indices indices;
    filter.filter(indices);
    kept->assign(indices.begin(), indices.end());
    return true;
  } catch (const std::exception& e) {
    *error = e.what();
    return false;
  }
}
}
