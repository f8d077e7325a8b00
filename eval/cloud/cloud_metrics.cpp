#include "eval/cloud/cloud_metrics.h"

#include <algorithm>
#include <cmath>
#include <nanoflann.hpp>
#include <sstream>

#include "common/error.h"

namespace cenote::eval {
namespace {

// nanoflann's dataset interface over a vector of points.
struct PointsAdaptor {
  const std::vector<Eigen::Vector3f>& points;
  size_t kdtree_get_point_count() const { return points.size(); }
  float kdtree_get_pt(size_t i, size_t dim) const { return points[i][static_cast<int>(dim)]; }
  template <class Box>
  bool kdtree_get_bbox(Box&) const {
    return false;
  }
};

using KdTree =
    nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<float, PointsAdaptor>, PointsAdaptor, 3, uint32_t>;
constexpr size_t kLeafSize = 10;

// Fraction of sorted `values` strictly below t.
double fractionBelow(const std::vector<double>& sorted, double t) {
  return static_cast<double>(std::lower_bound(sorted.begin(), sorted.end(), t) - sorted.begin()) / sorted.size();
}

double fscore(double p, double r) { return p + r > 0.0 ? 2.0 * p * r / (p + r) : 0.0; }

}  // namespace

std::vector<double> nearestDistances(const std::vector<Eigen::Vector3f>& queries,
                                     const std::vector<Eigen::Vector3f>& reference) {
  if (reference.empty()) throw Error("nearest neighbours: the reference cloud is empty");
  if (reference.size() > std::numeric_limits<uint32_t>::max()) throw Error("nearest neighbours: more than 2^32 points");
  PointsAdaptor adaptor{reference};
  KdTree tree(3, adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(kLeafSize));
  tree.buildIndex();
  std::vector<double> distances(queries.size());
  const auto n = static_cast<int64_t>(queries.size());
#pragma omp parallel for schedule(dynamic, 4096)
  for (int64_t i = 0; i < n; ++i) {
    uint32_t index = 0;
    float d2 = 0.0f;
    tree.knnSearch(queries[i].data(), 1, &index, &d2);
    // Recomputed in double from the found point: the tree's float sum is only used to search.
    distances[i] = (queries[i].cast<double>() - reference[index].cast<double>()).norm();
  }
  return distances;
}

CloudEvaluation evaluateDistances(std::vector<double> source_to_target, std::vector<double> target_to_source,
                                  const CloudEvaluationOptions& options) {
  if (!(options.threshold_m > 0.0) || !std::isfinite(options.threshold_m)) {
    std::ostringstream text;
    text << "threshold " << options.threshold_m << " m: must be finite and > 0";
    throw Error(text.str());
  }
  if (!(options.curve_max_m >= 0.0) || !std::isfinite(options.curve_max_m) || options.curve_steps < 1 ||
      options.curve_steps > 100000) {
    std::ostringstream text;
    text << "curve up to " << options.curve_max_m << " m in " << options.curve_steps
         << " steps: need a finite maximum >= 0 (0 = 5 x threshold) and 1..100000 steps";
    throw Error(text.str());
  }
  if (source_to_target.empty() || target_to_source.empty()) {
    throw Error(std::string("cloud metrics: the ") + (source_to_target.empty() ? "source" : "target") +
                " cloud has no point");
  }
  CloudEvaluation e;
  e.source_points = source_to_target.size();
  e.target_points = target_to_source.size();
  e.threshold_m = options.threshold_m;
  double sum = 0.0;
  for (double d : source_to_target) {
    sum += d;
    e.source_histogram.add(d);
  }
  e.accuracy_m = sum / source_to_target.size();
  sum = 0.0;
  for (double d : target_to_source) {
    sum += d;
    e.target_histogram.add(d);
  }
  e.completeness_m = sum / target_to_source.size();
  std::sort(source_to_target.begin(), source_to_target.end());
  std::sort(target_to_source.begin(), target_to_source.end());
  e.accuracy_median_m = medianInPlace(source_to_target);
  e.completeness_median_m = medianInPlace(target_to_source);
  std::sort(source_to_target.begin(), source_to_target.end());  // medianInPlace may reorder
  std::sort(target_to_source.begin(), target_to_source.end());
  e.precision = fractionBelow(source_to_target, options.threshold_m);
  e.recall = fractionBelow(target_to_source, options.threshold_m);
  e.fscore = fscore(e.precision, e.recall);
  const double max_m = options.curve_max_m > 0.0 ? options.curve_max_m : 5.0 * options.threshold_m;
  for (int i = 1; i <= options.curve_steps; ++i) {
    CurvePoint c;
    c.threshold_m = max_m * i / options.curve_steps;
    c.precision = fractionBelow(source_to_target, c.threshold_m);
    c.recall = fractionBelow(target_to_source, c.threshold_m);
    c.fscore = fscore(c.precision, c.recall);
    e.curve.push_back(c);
  }
  return e;
}

CloudEvaluation evaluateClouds(const std::vector<Eigen::Vector3f>& source, const std::vector<Eigen::Vector3f>& target,
                               const CloudEvaluationOptions& options) {
  if (source.empty() || target.empty()) {
    throw Error(std::string("cloud metrics: the ") + (source.empty() ? "source" : "target") + " cloud has no point");
  }
  return evaluateDistances(nearestDistances(source, target), nearestDistances(target, source), options);
}

}  // namespace cenote::eval
