// metrics_json.h: the evaluation results as JSON documents, the numbers `--json FILE` writes and the
// plot script and the HTML report read.
// Top-level names (units: metres; fractions in [0, 1]; a value that does not exist, e.g. the MAE of
// no pixel, is null):
//   depth:       kind = "depth", mae, mom, coverage, frames_matched, common_px, frames[], histogram
//   cloud:       kind = "cloud", accuracy, completeness, precision, recall, fscore, threshold,
//                accuracy_median, completeness_median, source_points, target_points, curve[], histograms
//   trajectory:  kind = "trajectory", ate_rmse, ate_mean, ate_median, ate_max, alignment, scale,
//                pairs, unmatched_estimate, unmatched_reference, trajectory{t_s, reference, aligned, error_m}
// Threads: free functions, independent.
#pragma once

#include <string>
#include <vector>

#include "eval/cloud/cloud_metrics.h"
#include "eval/depth/depth_metrics.h"
#include "eval/trajectory/trajectory_alignment.h"

namespace cenote::eval {

// A frame whose error map is drawn: PFM files the plot script reads.
struct HeatmapSample {
  std::string name, error_pfm, reference_pfm;  // reference_pfm may be empty
  double mean_abs_m = 0.0, median_abs_m = 0.0;
};

// Extra fields any document may carry (inputs, so a report can say what was compared).
struct JsonInputs {
  std::string estimate, reference;
};

std::string toJson(const DepthEvaluation& e, const JsonInputs& inputs, const std::vector<HeatmapSample>& heatmaps = {});
std::string toJson(const CloudEvaluation& e, const JsonInputs& inputs);
std::string toJson(const TrajectoryEvaluation& e, const JsonInputs& inputs);

// Writes text to path (via a temporary file). @throws cenote::Error when it cannot be written.
void writeTextFile(const std::string& path, const std::string& text);

}  // namespace cenote::eval
