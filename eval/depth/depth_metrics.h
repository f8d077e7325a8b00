// depth_metrics.h: the paper's depth-map metrics, an estimate against a reference (ground truth or
// COLMAP), on pixels valid in both maps.
//   per frame:  mean and median of |Z_est - Z_ref|, coverage = common / reference-valid pixels
//   dataset:    MAE = mean of |Z_est - Z_ref| over every common pixel of every frame (pooled),
//               MoM = median over frames of the per-frame median, coverage = sum common / sum reference
// Units: metres (depth along the optical axis). Maps are CV_32FC1 with NaN = invalid (see
// depth_folder.h, which loads them so).
// Threads: free functions, independent.
#pragma once

#include <cstdint>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "eval/depth/depth_folder.h"
#include "eval/stats/stats.h"

namespace cenote::eval {

struct FrameDepthError {
  std::string name;
  DepthFile estimate_file, reference_file;  // where the maps came from (empty for compareDepthMaps)
  int64_t estimate_px = 0;                  // valid in the estimate
  int64_t reference_px = 0;                 // valid in the reference
  int64_t common_px = 0;                    // valid in both: the pixels compared
  double sum_abs_m = 0.0;                   // sum of |error| over common pixels
  double mean_abs_m = 0.0;                  // NaN when no common pixel
  double median_abs_m = 0.0;                // NaN when no common pixel
  double coverage() const { return reference_px > 0 ? static_cast<double>(common_px) / reference_px : 0.0; }
};

// Compares two maps of one size. When `abs_error` is given it receives CV_32FC1 |error| (NaN where
// not compared); when `histogram` is given each error is added to it.
// @throws cenote::Error naming `name` when the sizes differ or a map is not CV_32FC1.
FrameDepthError compareDepthMaps(const cv::Mat& estimate, const cv::Mat& reference, const std::string& name,
                                 cv::Mat* abs_error = nullptr, LogHistogram* histogram = nullptr);

struct DepthEvaluationOptions {
  bool prefer_photometric = false;  // COLMAP: *.photometric.bin over *.geometric.bin
  double reference_scale = 1.0;     // multiplies reference depths (COLMAP models have arbitrary scale)
  double max_depth_m = 0.0;         // > 0: pixels beyond this in either map are not compared
  // > 0: an estimate whose name is a number and has no reference of the same name is paired with
  // the reference whose numeric name is nearest, when within this (in the names' unit, e.g. ns);
  // for writers that round timestamps differently. Each reference is used once at most.
  double name_tolerance = 0.0;
};

struct DepthEvaluation {
  std::vector<FrameDepthError> frames;         // matched frames, sorted by name
  std::vector<std::string> only_in_estimate;   // names without a reference (not evaluated)
  std::vector<std::string> only_in_reference;  // names without an estimate (not evaluated)
  double mae_m = 0.0;                          // NaN when no pixel was compared
  double mom_m = 0.0;                          // NaN when no frame had a common pixel
  double coverage = 0.0;                       // in [0, 1]
  int64_t common_px = 0;
  LogHistogram histogram;  // of |error| over every common pixel
};

// Matches the two folders' depth maps by name (depth_folder.h) and evaluates every pair.
// @throws cenote::Error when a folder is missing, holds no depth map, no name is in both, a file is
//         malformed, sizes differ for one name, or an option is out of range.
DepthEvaluation evaluateDepthFolders(const std::string& estimate_dir, const std::string& reference_dir,
                                     const DepthEvaluationOptions& options = {});

// |error| map of one evaluated frame (CV_32FC1, NaN where not compared), re-read from its files
// with the same options. @throws cenote::Error as evaluateDepthFolders.
cv::Mat frameErrorMap(const FrameDepthError& frame, const DepthEvaluationOptions& options = {});

// Dataset numbers from per-frame results (used by evaluateDepthFolders; exposed for tests).
void summarizeFrames(DepthEvaluation& evaluation);

}  // namespace cenote::eval
