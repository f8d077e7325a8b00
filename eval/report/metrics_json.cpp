#include "eval/report/metrics_json.h"

#include <cmath>
#include <filesystem>
#include <fstream>

#include "common/atomic_file.h"
#include "common/error.h"
#include "eval/report/metrics_document.h"

namespace cenote::eval {
namespace {

Json histogramJson(const LogHistogram& h) {
  Json edges = Json::array(), counts = Json::array();
  for (int i = 0; i <= h.numBins(); ++i) edges.push_back(LogHistogram::edge(i));
  for (int64_t c : h.counts()) counts.push_back(c);
  return {{"edges", edges}, {"counts", counts}};
}

Json xyz(const Eigen::Vector3d& p) { return Json::array({p.x(), p.y(), p.z()}); }

}  // namespace

std::string toJson(const DepthEvaluation& e, const JsonInputs& inputs, const std::vector<HeatmapSample>& heatmaps) {
  Json j = metricsDocument("depth", "metres; coverage as a fraction", inputs.estimate, inputs.reference);
  j["mae"] = jsonNumber(e.mae_m);
  j["mom"] = jsonNumber(e.mom_m);
  j["coverage"] = jsonNumber(e.coverage);
  j["frames_matched"] = e.frames.size();
  j["common_px"] = e.common_px;
  j["only_in_estimate"] = e.only_in_estimate;
  j["only_in_reference"] = e.only_in_reference;
  Json frames = Json::array();
  for (const FrameDepthError& f : e.frames) {
    frames.push_back({{"name", f.name},
                      {"mean_abs_m", jsonNumber(f.mean_abs_m)},
                      {"median_abs_m", jsonNumber(f.median_abs_m)},
                      {"coverage", jsonNumber(f.coverage())},
                      {"common_px", f.common_px},
                      {"reference_px", f.reference_px},
                      {"estimate_px", f.estimate_px}});
  }
  j["frames"] = frames;
  j["histogram"] = histogramJson(e.histogram);
  if (!heatmaps.empty()) {
    Json list = Json::array();
    for (const HeatmapSample& h : heatmaps) {
      list.push_back({{"name", h.name},
                      {"error_pfm", h.error_pfm},
                      {"reference_pfm", h.reference_pfm},
                      {"mean_abs_m", jsonNumber(h.mean_abs_m)},
                      {"median_abs_m", jsonNumber(h.median_abs_m)}});
    }
    j["heatmaps"] = list;
  }
  return j.dump(2) + "\n";
}

std::string toJson(const CloudEvaluation& e, const JsonInputs& inputs) {
  Json j = metricsDocument("cloud", "metres; precision, recall and fscore as fractions", inputs.estimate, inputs.reference);
  j["accuracy"] = jsonNumber(e.accuracy_m);
  j["completeness"] = jsonNumber(e.completeness_m);
  j["precision"] = jsonNumber(e.precision);
  j["recall"] = jsonNumber(e.recall);
  j["fscore"] = jsonNumber(e.fscore);
  j["threshold"] = jsonNumber(e.threshold_m);
  j["accuracy_median"] = jsonNumber(e.accuracy_median_m);
  j["completeness_median"] = jsonNumber(e.completeness_median_m);
  j["source_points"] = e.source_points;
  j["target_points"] = e.target_points;
  Json curve = Json::array();
  for (const CurvePoint& c : e.curve) {
    curve.push_back(
        {{"threshold_m", c.threshold_m}, {"precision", c.precision}, {"recall", c.recall}, {"fscore", c.fscore}});
  }
  j["curve"] = curve;
  j["source_histogram"] = histogramJson(e.source_histogram);
  j["target_histogram"] = histogramJson(e.target_histogram);
  return j.dump(2) + "\n";
}

std::string toJson(const TrajectoryEvaluation& e, const JsonInputs& inputs) {
  Json j = metricsDocument("trajectory", "metres, seconds", inputs.estimate, inputs.reference);
  j["ate_rmse"] = jsonNumber(e.ate_rmse_m);
  j["ate_mean"] = jsonNumber(e.ate_mean_m);
  j["ate_median"] = jsonNumber(e.ate_median_m);
  j["ate_max"] = jsonNumber(e.ate_max_m);
  j["alignment"] = toString(e.alignment);
  j["scale"] = jsonNumber(e.T_ref_est.scale);
  j["pairs"] = e.pairs.t_s.size();
  j["unmatched_estimate"] = e.pairs.unmatched_estimate;
  j["unmatched_reference"] = e.pairs.unmatched_reference;
  Json rotation = Json::array();
  for (int r = 0; r < 3; ++r) rotation.push_back({e.T_ref_est.R(r, 0), e.T_ref_est.R(r, 1), e.T_ref_est.R(r, 2)});
  j["T_ref_est"] = {{"scale", jsonNumber(e.T_ref_est.scale)}, {"R", rotation}, {"t", xyz(e.T_ref_est.t)}};
  Json t = Json::array(), ref = Json::array(), aligned = Json::array(), error = Json::array();
  for (size_t i = 0; i < e.pairs.t_s.size(); ++i) {
    t.push_back(e.pairs.t_s[i]);
    ref.push_back(xyz(e.pairs.reference[i]));
    aligned.push_back(xyz(e.aligned[i]));
    error.push_back(e.errors_m[i]);
  }
  j["trajectory"] = {{"t_s", t}, {"reference", ref}, {"aligned", aligned}, {"error_m", error}};
  return j.dump(2) + "\n";
}

void writeTextFile(const std::string& path, const std::string& text) {
  writeFileAtomically(path, text, Durability::kDurable);
}

}  // namespace cenote::eval
