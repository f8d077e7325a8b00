// `cenote eval`: the paper's evaluation (eval/) from the command line.
//   cenote eval depth  --estimate DIR --reference DIR       depth maps matched by image name
//   cenote eval cloud  --source S.ply --target T.ply        point clouds (PLY or PCD)
//   cenote eval traj   --estimate E --reference R           trajectories (TUM, EuRoC, KITTI, COLMAP)
//   cenote eval map    --estimate A.vdb --reference B.bt    occupancy agreement (eval_map_command.cpp)
//   cenote eval report DIR                                  one self-contained HTML page
// Each metric command prints a table; --json FILE writes the numbers (eval/report/metrics_json.h),
// --plot DIR writes PNG plots (matplotlib, eval/report/plots.h).
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <sstream>

#include "apps/cenote/commands.h"
#include "apps/cenote/subcommand.h"
#include "common/error.h"
#include "common/size_format.h"
#include "eval/cloud/cloud_io.h"
#include "eval/cloud/cloud_metrics.h"
#include "eval/cloud/voxel_downsample.h"
#include "eval/depth/depth_metrics.h"
#include "eval/report/html_report.h"
#include "eval/report/metrics_json.h"
#include "eval/report/plots.h"
#include "eval/trajectory/trajectory_alignment.h"
#include "eval/trajectory/trajectory_io.h"
#include "io/image/image_io.h"
#include "pipeline/dataset/stereo_dataset.h"

namespace cenote::apps {
namespace {

namespace fs = std::filesystem;

struct OutputOptions {
  std::string json, plot;
};

void addOutputOptions(CLI::App* cmd, OutputOptions& o) {
  cmd->add_option("--json", o.json, "Write the numbers as JSON to this file");
  cmd->add_option("--plot", o.plot, "Write PNG plots into this folder (needs python3-matplotlib)");
}

std::string num(double v, const char* unit = "", int precision = 4) {
  if (!std::isfinite(v)) return "n/a";
  char text[64];
  std::snprintf(text, sizeof(text), "%.*g%s", precision, v, unit);
  return text;
}

std::string pct(double v) {
  if (!std::isfinite(v)) return "n/a";
  char text[32];
  std::snprintf(text, sizeof(text), "%.2f %%", 100.0 * v);
  return text;
}

void printTable(const std::string& title, const std::vector<std::pair<std::string, std::string>>& rows) {
  size_t width = 0;
  for (const auto& [name, value] : rows) width = std::max(width, name.size());
  std::cout << title << "\n";
  for (const auto& [name, value] : rows) {
    std::cout << "  " << name << std::string(width - name.size() + 2, ' ') << value << "\n";
  }
}

// A scratch folder for files handed to the plot script, removed when it goes out of scope.
class ScratchDir {
 public:
  ScratchDir() : path_(fs::temp_directory_path() / ("cenote_eval_" + std::to_string(getpid()))) {
    fs::create_directories(path_);
  }
  ~ScratchDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
  std::string operator/(const std::string& name) const { return (path_ / name).string(); }

 private:
  fs::path path_;
};

void writeOutputs(const OutputOptions& o, const std::string& json, const std::string& plot_json) {
  if (!o.json.empty()) {
    eval::writeTextFile(o.json, json);
    std::cout << "numbers: " << o.json << "\n";
  }
  if (!o.plot.empty()) {
    const std::vector<std::string> pngs = eval::writePlots(plot_json, o.plot);
    std::cout << "plots: " << pngs.size() << " PNG files in " << o.plot << "\n";
  }
}

// --json and --plot of a result whose plots are drawn from its JSON alone (written as <name>.json
// into a scratch folder for the plotter).
void writeOutputsPlottedFromJson(const OutputOptions& o, const std::string& json, const std::string& name) {
  if (o.plot.empty()) return writeOutputs(o, json, "");
  const ScratchDir scratch;
  const std::string plot_json = scratch / (name + ".json");
  eval::writeTextFile(plot_json, json);
  writeOutputs(o, json, plot_json);
}

void checkOutputs(const OutputOptions& o) {
  if (!o.json.empty()) {
    const fs::path parent = fs::path(o.json).parent_path();
    if (!parent.empty() && !fs::is_directory(parent))
      throw Error("--json " + o.json + ": folder " + parent.string() + " does not exist");
  }
}

// ---- depth ----

struct DepthOptions {
  std::string estimate, reference;
  bool photometric = false;
  double reference_scale = 1.0, max_depth_m = 0.0, name_tolerance = 0.0;
  int heatmaps = 3;
  OutputOptions out;
};

// The best, median and worst frames by mean error (distinct, up to n).
std::vector<size_t> heatmapFrames(const eval::DepthEvaluation& e, int n) {
  std::vector<size_t> order;
  for (size_t i = 0; i < e.frames.size(); ++i) {
    if (e.frames[i].common_px > 0) order.push_back(i);
  }
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return e.frames[a].mean_abs_m > e.frames[b].mean_abs_m; });
  std::vector<size_t> chosen;
  if (order.empty() || n <= 0) return chosen;
  const int count = std::min<int>(n, static_cast<int>(order.size()));
  for (int k = 0; k < count; ++k) {
    const size_t pick = order[count == 1 ? 0 : k * (order.size() - 1) / (count - 1)];
    if (std::find(chosen.begin(), chosen.end(), pick) == chosen.end()) chosen.push_back(pick);
  }
  return chosen;
}

void runDepth(const DepthOptions& o) {
  checkOutputs(o.out);
  eval::DepthEvaluationOptions options;
  options.prefer_photometric = o.photometric;
  options.reference_scale = o.reference_scale;
  options.max_depth_m = o.max_depth_m;
  options.name_tolerance = o.name_tolerance;
  const eval::DepthEvaluation e = eval::evaluateDepthFolders(o.estimate, o.reference, options);
  printTable("depth maps: " + o.estimate + " against " + o.reference,
             {{"frames matched", std::to_string(e.frames.size())},
              {"only in estimate", std::to_string(e.only_in_estimate.size())},
              {"only in reference", std::to_string(e.only_in_reference.size())},
              {"pixels compared", std::to_string(e.common_px)},
              {"MAE", num(e.mae_m, " m")},
              {"MoM", num(e.mom_m, " m")},
              {"coverage", pct(e.coverage)}});
  if (e.frames.size() <= 20) {
    std::cout << "  frame                          mean m   median m   coverage\n";
    for (const auto& f : e.frames) {
      char line[160];
      std::snprintf(line, sizeof(line), "  %-28s %9s %10s %10s\n", f.name.c_str(), num(f.mean_abs_m).c_str(),
                    num(f.median_abs_m).c_str(), pct(f.coverage()).c_str());
      std::cout << line;
    }
  }
  const eval::JsonInputs inputs{o.estimate, o.reference};
  std::string plot_json;
  std::unique_ptr<ScratchDir> scratch;
  if (!o.out.plot.empty()) {
    scratch = std::make_unique<ScratchDir>();
    std::vector<eval::HeatmapSample> samples;
    for (size_t i : heatmapFrames(e, o.heatmaps)) {
      const eval::FrameDepthError& f = e.frames[i];
      eval::HeatmapSample s;
      s.name = f.name;
      s.mean_abs_m = f.mean_abs_m;
      s.median_abs_m = f.median_abs_m;
      s.error_pfm = *scratch / (std::to_string(i) + ".error.pfm");
      s.reference_pfm = *scratch / (std::to_string(i) + ".reference.pfm");
      io::writePfm(s.error_pfm, eval::frameErrorMap(f, options));
      io::writePfm(s.reference_pfm, eval::loadDepthMap(f.reference_file) * o.reference_scale);
      samples.push_back(s);
    }
    plot_json = *scratch / "depth.json";
    eval::writeTextFile(plot_json, eval::toJson(e, inputs, samples));
  }
  writeOutputs(o.out, eval::toJson(e, inputs), plot_json);
}

// ---- cloud ----

struct CloudOptions {
  std::string source, target;
  double voxel_m = 0.0;
  eval::CloudEvaluationOptions metrics;
  OutputOptions out;
};

std::vector<Eigen::Vector3f> loadCloud(const std::string& path, double voxel_m, const char* role) {
  eval::Cloud cloud = eval::readCloud(path);
  if (cloud.points.empty()) throw Error(std::string(role) + " " + path + ": the cloud has no point");
  if (cloud.non_finite_dropped > 0) {
    std::cerr << "note: " << path << ": " << cloud.non_finite_dropped << " points with NaN/inf coordinates skipped\n";
  }
  return eval::voxelDownsample(cloud.points, voxel_m);
}

// --target: a cloud file, or a dataset folder that ships a reference cloud (the paper's colmap.ply).
std::string targetCloud(const std::string& target) {
  if (!std::filesystem::is_directory(target)) return target;
  const std::optional<std::string> cloud = pipeline::openDataset(target)->referenceCloud();
  if (!cloud) throw NotFoundError("--target " + target + ": the dataset has no reference cloud (colmap.ply)");
  return *cloud;
}

void runCloud(CloudOptions o) {
  checkOutputs(o.out);
  if (!(o.voxel_m >= 0.0)) throw Error("--voxel " + num(o.voxel_m) + ": must be >= 0 (0 = no downsampling)");
  o.target = targetCloud(o.target);
  const std::vector<Eigen::Vector3f> source = loadCloud(o.source, o.voxel_m, "--source");
  const std::vector<Eigen::Vector3f> target = loadCloud(o.target, o.voxel_m, "--target");
  const eval::CloudEvaluation e = eval::evaluateClouds(source, target, o.metrics);
  const std::string at = " at " + num(e.threshold_m, " m");
  printTable("point clouds: " + o.source + " (source) against " + o.target + " (target)",
             {{"points (source / target)", std::to_string(e.source_points) + " / " + std::to_string(e.target_points) +
                                               (o.voxel_m > 0 ? " after " + num(o.voxel_m, " m") + " voxels" : "")},
              {"accuracy", num(e.accuracy_m, " m") + " (median " + num(e.accuracy_median_m, " m") + ")"},
              {"completeness", num(e.completeness_m, " m") + " (median " + num(e.completeness_median_m, " m") + ")"},
              {"precision" + at, pct(e.precision)},
              {"recall" + at, pct(e.recall)},
              {"F-score" + at, pct(e.fscore)}});
  const std::string json = eval::toJson(e, {o.source, o.target});
  writeOutputsPlottedFromJson(o.out, json, "cloud");
}

// ---- trajectory ----

struct TrajOptions {
  std::string estimate, reference, align = "sim3", format = "auto", reference_format, estimate_times, reference_times;
  double tolerance_s = 0.02;
  OutputOptions out;
};

void runTraj(const TrajOptions& o) {
  checkOutputs(o.out);
  const auto est_format = eval::parseTrajectoryFileFormat(o.format);
  const auto ref_format = eval::parseTrajectoryFileFormat(o.reference_format.empty() ? o.format : o.reference_format);
  const auto estimate = eval::readTrajectoryFile(o.estimate, est_format, o.estimate_times);
  const auto reference = eval::readTrajectoryFile(o.reference, ref_format, o.reference_times);
  eval::TrajectoryEvaluationOptions options;
  options.alignment = eval::parseAlignment(o.align);
  options.tolerance_s = o.tolerance_s;
  const eval::TrajectoryEvaluation e = eval::evaluateTrajectory(estimate, reference, options);
  printTable("trajectory: " + o.estimate + " against " + o.reference,
             {{"poses (estimate / reference)", std::to_string(estimate.size()) + " / " + std::to_string(reference.size())},
              {"associated", std::to_string(e.pairs.t_s.size()) + " within " + num(o.tolerance_s, " s")},
              {"alignment", std::string(eval::toString(e.alignment)) + ", scale " + num(e.T_ref_est.scale, "", 6)},
              {"ATE RMSE", num(e.ate_rmse_m, " m")},
              {"ATE mean", num(e.ate_mean_m, " m")},
              {"ATE median", num(e.ate_median_m, " m")},
              {"ATE max", num(e.ate_max_m, " m")}});
  const std::string json = eval::toJson(e, {o.estimate, o.reference});
  writeOutputsPlottedFromJson(o.out, json, "trajectory");
}

// ---- report ----

struct ReportOptions {
  std::string dir, out;
  eval::HtmlReportOptions html;
};

void runReport(const ReportOptions& o) {
  const std::string path = eval::writeHtmlReport(o.dir, o.out, o.html);
  std::cout << "report: " << path << " (" << formatBytes(static_cast<double>(fs::file_size(path))) << ")\n";
}

}  // namespace

void registerEvalCommand(CLI::App& app) {
  CLI::App* eval_cmd = app.add_subcommand("eval", "Evaluate depth maps, point clouds and trajectories; HTML report");
  eval_cmd->require_subcommand(1);

  const auto [depth, d] = addSubcommand<DepthOptions>(*eval_cmd, "depth",
                                                      "Depth maps against a reference (MAE, MoM, coverage)", runDepth);
  depth->add_option("--estimate", d->estimate, "Folder of estimated depth maps (PFM, 16-bit PNG mm, COLMAP .bin)")
      ->required();
  depth->add_option("--reference", d->reference, "Folder of reference depth maps, or a COLMAP workspace")->required();
  depth->add_flag("--photometric", d->photometric, "COLMAP: use *.photometric.bin rather than *.geometric.bin");
  depth->add_option("--reference-scale", d->reference_scale, "Multiply reference depths by this (COLMAP scale)")
      ->capture_default_str();
  depth->add_option("--max-depth", d->max_depth_m, "Compare only depths up to this, metres (0 = all)")
      ->capture_default_str();
  depth
      ->add_option("--name-tolerance", d->name_tolerance,
                   "Pair numeric names (timestamps) this close when no name matches exactly (0 = exact)")
      ->capture_default_str();
  depth->add_option("--heatmaps", d->heatmaps, "With --plot: error maps of this many frames (best..worst)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  addOutputOptions(depth, d->out);

  const auto [cloud, c] = addSubcommand<CloudOptions>(*eval_cmd, "cloud",
                                                      "Point clouds: accuracy, completeness, precision, recall", runCloud);
  cloud->add_option("--source", c->source, "Estimated cloud (PLY or PCD)")->required();
  cloud->add_option("--target", c->target, "Reference cloud (PLY or PCD), or a dataset folder with colmap.ply")->required();
  cloud->add_option("--threshold", c->metrics.threshold_m, "Precision/recall distance, metres")->capture_default_str();
  cloud->add_option("--voxel", c->voxel_m, "Voxel-downsample both clouds first, metres (paper: 0.001; 0 = none)")
      ->capture_default_str();
  cloud->add_option("--curve-max", c->metrics.curve_max_m, "Curves up to this threshold, metres (0 = 5 x threshold)");
  cloud->add_option("--curve-steps", c->metrics.curve_steps, "Thresholds on the curves")->capture_default_str();
  addOutputOptions(cloud, c->out);

  const auto [traj, t] = addSubcommand<TrajOptions>(*eval_cmd, "traj", "Trajectories: ATE after Umeyama alignment",
                                                    runTraj);
  traj->add_option("--estimate", t->estimate, "Estimated trajectory")->required();
  traj->add_option("--reference", t->reference, "Reference trajectory")->required();
  traj->add_option("--align", t->align, "Alignment")->capture_default_str()->check(CLI::IsMember({"sim3", "se3", "none"}));
  traj->add_option("--format", t->format, "File format (of both, unless --reference-format)")
      ->capture_default_str()
      ->check(CLI::IsMember({"auto", "tum", "euroc", "kitti", "colmap", "okvis"}));
  traj->add_option("--reference-format", t->reference_format, "Format of the reference when it differs")
      ->check(CLI::IsMember({"auto", "tum", "euroc", "kitti", "colmap", "okvis"}));
  traj->add_option("--estimate-times", t->estimate_times, "KITTI: timestamps file of the estimate");
  traj->add_option("--reference-times", t->reference_times, "KITTI: timestamps file of the reference");
  traj->add_option("--tolerance", t->tolerance_s, "Largest time difference of an associated pair, s")
      ->capture_default_str();
  addOutputOptions(traj, t->out);

  registerEvalMapCommand(*eval_cmd);

  const auto [report, r] = addSubcommand<ReportOptions>(*eval_cmd, "report",
                                                        "One self-contained HTML page for a run folder", runReport);
  report->add_option("dir", r->dir, "Run folder (report.json, *.json metrics, plots/, depth maps)")->required();
  report->add_option("--out", r->out, "HTML file (default DIR/report.html)");
  report->add_option("--title", r->html.title, "Page title")->capture_default_str();
  report->add_option("--samples", r->html.max_samples, "Frames shown as samples")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
}

}  // namespace cenote::apps
