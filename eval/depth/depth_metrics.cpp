#include "eval/depth/depth_metrics.h"

#include <cmath>
#include <algorithm>
#include <limits>
#include <map>
#include <set>
#include <sstream>

#include "common/error.h"
#include "eval/depth/depth_folder.h"

namespace cenote::eval {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string sizeText(const cv::Mat& m) { return std::to_string(m.cols) + "x" + std::to_string(m.rows); }

void checkOptions(const DepthEvaluationOptions& o) {
  if (!(o.reference_scale > 0.0) || !std::isfinite(o.reference_scale)) {
    std::ostringstream text;
    text << "reference scale " << o.reference_scale << ": must be a finite number > 0";
    throw Error(text.str());
  }
  if (!(o.name_tolerance >= 0.0) || !std::isfinite(o.name_tolerance)) {
    std::ostringstream text;
    text << "name tolerance " << o.name_tolerance << ": must be finite and >= 0 (0 = exact names)";
    throw Error(text.str());
  }
  if (!(o.max_depth_m >= 0.0) || !std::isfinite(o.max_depth_m)) {
    std::ostringstream text;
    text << "max depth " << o.max_depth_m << " m: must be finite and >= 0 (0 = no limit)";
    throw Error(text.str());
  }
}

// Scales the reference and drops depths beyond the limit (NaN).
void prepare(cv::Mat& depth, double scale, double max_depth_m) {
  if (scale != 1.0) depth *= scale;
  if (max_depth_m <= 0.0) return;
  const auto limit = static_cast<float>(max_depth_m);
  for (int y = 0; y < depth.rows; ++y) {
    float* row = depth.ptr<float>(y);
    for (int x = 0; x < depth.cols; ++x) {
      if (row[x] > limit) row[x] = std::numeric_limits<float>::quiet_NaN();
    }
  }
}

FrameDepthError compareFiles(const DepthFile& est_file, const DepthFile& ref_file, const std::string& name,
                             const DepthEvaluationOptions& o, cv::Mat* abs_error, LogHistogram* histogram) {
  cv::Mat est = loadDepthMap(est_file);
  cv::Mat ref = loadDepthMap(ref_file);
  if (est.size() != ref.size()) {
    throw Error("'" + name + "': estimate " + est_file.path + " is " + sizeText(est) + " but reference " + ref_file.path +
                " is " + sizeText(ref));
  }
  prepare(est, 1.0, o.max_depth_m);
  prepare(ref, o.reference_scale, o.max_depth_m);
  FrameDepthError frame = compareDepthMaps(est, ref, name, abs_error, histogram);
  frame.estimate_file = est_file;
  frame.reference_file = ref_file;
  return frame;
}

std::string examples(const std::map<std::string, DepthFile>& files) {
  std::string text;
  int n = 0;
  for (const auto& [key, file] : files) {
    if (n++ == 3) break;
    text += (text.empty() ? "" : ", ") + ("'" + key + "'");
  }
  return text;
}

bool numericName(const std::string& name, long double& value) {
  char* end = nullptr;
  value = std::strtold(name.c_str(), &end);
  return !name.empty() && end != name.c_str() && *end == '\0';
}

// Pairs estimate names without an exact reference with the nearest numeric reference name.
std::map<std::string, std::string> numericPairs(const std::map<std::string, DepthFile>& estimates,
                                                const std::map<std::string, DepthFile>& references, double tolerance) {
  std::map<std::string, std::string> pairs;
  if (tolerance <= 0.0) return pairs;
  std::vector<std::pair<long double, std::string>> numeric;
  for (const auto& [key, file] : references) {
    long double v = 0;
    if (!estimates.count(key) && numericName(key, v)) numeric.emplace_back(v, key);
  }
  std::sort(numeric.begin(), numeric.end());
  std::set<std::string> used;
  for (const auto& [key, file] : estimates) {
    long double v = 0;
    if (references.count(key) || !numericName(key, v) || numeric.empty()) continue;
    auto it = std::lower_bound(numeric.begin(), numeric.end(), std::make_pair(v, std::string()));
    const std::pair<long double, std::string>* best = nullptr;
    for (auto c : {it, it == numeric.begin() ? it : std::prev(it)}) {
      if (c == numeric.end()) continue;
      if (!best || std::abs(c->first - v) < std::abs(best->first - v)) best = &*c;
    }
    if (best && std::abs(best->first - v) <= tolerance && !used.count(best->second)) {
      pairs[key] = best->second;
      used.insert(best->second);
    }
  }
  return pairs;
}

}  // namespace

FrameDepthError compareDepthMaps(const cv::Mat& estimate, const cv::Mat& reference, const std::string& name,
                                 cv::Mat* abs_error, LogHistogram* histogram) {
  if (estimate.type() != CV_32FC1 || reference.type() != CV_32FC1) {
    throw Error("'" + name + "': depth maps must be single-channel float");
  }
  if (estimate.size() != reference.size()) {
    throw Error("'" + name + "': estimate is " + sizeText(estimate) + " but reference is " + sizeText(reference));
  }
  FrameDepthError frame;
  frame.name = name;
  if (abs_error) abs_error->create(estimate.size(), CV_32FC1);
  std::vector<double> errors;
  errors.reserve(estimate.total());
  for (int y = 0; y < estimate.rows; ++y) {
    const float* e = estimate.ptr<float>(y);
    const float* r = reference.ptr<float>(y);
    float* out = abs_error ? abs_error->ptr<float>(y) : nullptr;
    for (int x = 0; x < estimate.cols; ++x) {
      const bool e_ok = std::isfinite(e[x]) && e[x] > 0.0f;
      const bool r_ok = std::isfinite(r[x]) && r[x] > 0.0f;
      frame.estimate_px += e_ok;
      frame.reference_px += r_ok;
      float err = std::numeric_limits<float>::quiet_NaN();
      if (e_ok && r_ok) {
        const double d = std::abs(static_cast<double>(e[x]) - static_cast<double>(r[x]));
        errors.push_back(d);
        frame.sum_abs_m += d;
        if (histogram) histogram->add(d);
        err = static_cast<float>(d);
      }
      if (out) out[x] = err;
    }
  }
  frame.common_px = static_cast<int64_t>(errors.size());
  frame.mean_abs_m = errors.empty() ? kNaN : frame.sum_abs_m / errors.size();
  frame.median_abs_m = medianInPlace(errors);
  return frame;
}

void summarizeFrames(DepthEvaluation& evaluation) {
  double sum = 0.0;
  int64_t common = 0, reference = 0;
  std::vector<double> medians;
  for (const FrameDepthError& f : evaluation.frames) {
    sum += f.sum_abs_m;
    common += f.common_px;
    reference += f.reference_px;
    if (f.common_px > 0) medians.push_back(f.median_abs_m);
  }
  evaluation.common_px = common;
  evaluation.mae_m = common > 0 ? sum / common : kNaN;
  evaluation.mom_m = medianInPlace(medians);
  evaluation.coverage = reference > 0 ? static_cast<double>(common) / reference : 0.0;
}

DepthEvaluation evaluateDepthFolders(const std::string& estimate_dir, const std::string& reference_dir,
                                     const DepthEvaluationOptions& options) {
  checkOptions(options);
  const auto estimates = listDepthMaps(estimate_dir, options.prefer_photometric);
  const auto references = listDepthMaps(reference_dir, options.prefer_photometric);
  const char* kinds = " (*.pfm, 16-bit *.png, COLMAP *.geometric.bin / *.photometric.bin)";
  if (estimates.empty()) throw Error("estimate folder " + estimate_dir + " holds no depth map" + kinds);
  if (references.empty()) throw Error("reference folder " + reference_dir + " holds no depth map" + kinds);
  DepthEvaluation evaluation;
  const std::map<std::string, std::string> numeric = numericPairs(estimates, references, options.name_tolerance);
  std::set<std::string> matched_references;
  for (const auto& [key, file] : estimates) {
    auto ref = references.find(key);
    if (ref == references.end() && numeric.count(key)) ref = references.find(numeric.at(key));
    if (ref == references.end()) {
      evaluation.only_in_estimate.push_back(key);
      continue;
    }
    matched_references.insert(ref->first);
    evaluation.frames.push_back(compareFiles(file, ref->second, key, options, nullptr, &evaluation.histogram));
  }
  for (const auto& [key, file] : references) {
    if (!matched_references.count(key)) evaluation.only_in_reference.push_back(key);
  }
  if (evaluation.frames.empty()) {
    throw Error("no image name is in both " + estimate_dir + " (e.g. " + examples(estimates) + ") and " + reference_dir +
                " (e.g. " + examples(references) + ")");
  }
  summarizeFrames(evaluation);
  return evaluation;
}

cv::Mat frameErrorMap(const FrameDepthError& frame, const DepthEvaluationOptions& options) {
  checkOptions(options);
  cv::Mat error;
  compareFiles(frame.estimate_file, frame.reference_file, frame.name, options, &error, nullptr);
  return error;
}

}  // namespace cenote::eval
