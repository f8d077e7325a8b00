// cloud_metrics.h: the paper's point-cloud metrics, an estimate (source) against a reference
// (target), from nearest-neighbour distances.
//   accuracy     = mean distance from each source point to its nearest target point
//   completeness = mean distance from each target point to its nearest source point
//   precision(t) = fraction of source points whose distance is < t
//   recall(t)    = fraction of target points whose distance is < t
//   F-score(t)   = 2 P R / (P + R), 0 when P + R = 0
// (strict "<", as in the Tanks and Temples evaluation the paper's script follows).
// Units: metres; fractions in [0, 1]. Both clouds in one frame.
// Nearest neighbours come from a nanoflann k-d tree, queried from OpenMP threads; each distance is
// computed independently and sums are taken in point order, so results do not depend on the
// number of threads.
// Threads: free functions, independent (each uses OpenMP inside).
#pragma once

#include <Eigen/Core>
#include <vector>

#include "eval/stats/stats.h"

namespace cenote::eval {

// For every query point, the Euclidean distance to its nearest point of `reference`.
// @throws cenote::Error when `reference` is empty.
std::vector<double> nearestDistances(const std::vector<Eigen::Vector3f>& queries,
                                     const std::vector<Eigen::Vector3f>& reference);

struct CurvePoint {
  double threshold_m = 0.0;
  double precision = 0.0, recall = 0.0, fscore = 0.0;
};

struct CloudEvaluation {
  size_t source_points = 0, target_points = 0;  // after downsampling
  double threshold_m = 0.0;
  double accuracy_m = 0.0, completeness_m = 0.0;
  double accuracy_median_m = 0.0, completeness_median_m = 0.0;
  double precision = 0.0, recall = 0.0, fscore = 0.0;  // at threshold_m
  std::vector<CurvePoint> curve;                       // over curve thresholds, increasing
  LogHistogram source_histogram, target_histogram;     // of the two distance sets
};

struct CloudEvaluationOptions {
  double threshold_m = 0.1;  // the paper's 0.1 m
  double curve_max_m = 0.0;  // curve from curve_max_m / curve_steps to curve_max_m; 0: 5 x threshold
  int curve_steps = 50;
};

// Metrics at and around a threshold from the two distance sets (source->target, target->source).
// @throws cenote::Error when a set is empty or an option is out of range.
CloudEvaluation evaluateDistances(std::vector<double> source_to_target, std::vector<double> target_to_source,
                                  const CloudEvaluationOptions& options = {});

// nearestDistances both ways, then evaluateDistances.
CloudEvaluation evaluateClouds(const std::vector<Eigen::Vector3f>& source, const std::vector<Eigen::Vector3f>& target,
                               const CloudEvaluationOptions& options = {});

}  // namespace cenote::eval
