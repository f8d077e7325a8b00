#include "eval/trajectory/trajectory_alignment.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <sstream>
#include <tuple>

#include "common/enum_names.h"
#include "common/error.h"
#include "eval/stats/stats.h"

namespace cenote::eval {

constexpr EnumName<Alignment> kAlignmentNames[] = {
    {Alignment::kSim3, "sim3"}, {Alignment::kSe3, "se3"}, {Alignment::kNone, "none"}};

Alignment parseAlignment(const std::string& name) {
  return parseEnumName(kAlignmentNames, name, "alignment '" + name + "'");
}

const char* toString(Alignment alignment) { return enumName(kAlignmentNames, alignment); }

AssociatedPositions associate(const std::vector<io::StampedPose>& estimate, const std::vector<io::StampedPose>& reference,
                              double tolerance_s) {
  if (!(tolerance_s >= 0.0) || !std::isfinite(tolerance_s)) {
    std::ostringstream text;
    text << "association tolerance " << tolerance_s << " s: must be finite and >= 0";
    throw Error(text.str());
  }
  std::vector<io::StampedPose> ref = reference;
  std::stable_sort(ref.begin(), ref.end(), [](const auto& a, const auto& b) { return a.t_s < b.t_s; });
  std::vector<std::tuple<double, size_t, size_t>> candidates;  // |dt|, estimate index, reference index
  for (size_t i = 0; i < estimate.size(); ++i) {
    const double t = estimate[i].t_s;
    auto it = std::lower_bound(ref.begin(), ref.end(), t - tolerance_s,
                               [](const io::StampedPose& p, double v) { return p.t_s < v; });
    for (; it != ref.end() && it->t_s <= t + tolerance_s; ++it) {
      candidates.emplace_back(std::abs(it->t_s - t), i, static_cast<size_t>(it - ref.begin()));
    }
  }
  std::sort(candidates.begin(), candidates.end());
  std::vector<long> match(estimate.size(), -1);
  std::vector<bool> used(ref.size(), false);
  for (const auto& [dt, i, j] : candidates) {
    if (match[i] >= 0 || used[j]) continue;
    match[i] = static_cast<long>(j);
    used[j] = true;
  }
  std::vector<size_t> order(estimate.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return estimate[a].t_s < estimate[b].t_s; });
  AssociatedPositions pairs;
  for (size_t i : order) {
    if (match[i] < 0) continue;
    pairs.t_s.push_back(estimate[i].t_s);
    pairs.estimate.push_back(estimate[i].T_world_cam.translation());
    pairs.reference.push_back(ref[match[i]].T_world_cam.translation());
  }
  pairs.unmatched_estimate = estimate.size() - pairs.t_s.size();
  pairs.unmatched_reference = ref.size() - pairs.t_s.size();
  return pairs;
}

Similarity alignPositions(const std::vector<Eigen::Vector3d>& estimate, const std::vector<Eigen::Vector3d>& reference,
                          Alignment alignment) {
  if (estimate.size() != reference.size()) throw Error("alignment: position lists differ in length");
  Similarity result;
  if (alignment == Alignment::kNone) return result;
  if (estimate.size() < 3) {
    throw Error("alignment: " + std::to_string(estimate.size()) + " associated poses, need at least 3");
  }
  const auto n = static_cast<Eigen::Index>(estimate.size());
  Eigen::Matrix3Xd src(3, n), dst(3, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    src.col(i) = estimate[i];
    dst.col(i) = reference[i];
  }
  const Eigen::Vector3d mean = src.rowwise().mean();
  const double spread = (src.colwise() - mean).squaredNorm() / n;
  if (alignment == Alignment::kSim3 && !(spread > 0.0)) {
    throw Error("sim3 alignment: the estimated camera positions all coincide, no scale can be found (try --align se3)");
  }
  const Eigen::Matrix4d T = Eigen::umeyama(src, dst, alignment == Alignment::kSim3);
  const Eigen::Matrix3d sR = T.topLeftCorner<3, 3>();
  result.scale = alignment == Alignment::kSim3 ? std::cbrt(sR.determinant()) : 1.0;
  result.R = sR / result.scale;
  result.t = T.topRightCorner<3, 1>();
  if (!std::isfinite(result.scale) || !result.R.allFinite() || !result.t.allFinite()) {
    throw Error(std::string(toString(alignment)) + " alignment failed (degenerate positions)");
  }
  return result;
}

TrajectoryEvaluation evaluateTrajectory(const std::vector<io::StampedPose>& estimate,
                                        const std::vector<io::StampedPose>& reference,
                                        const TrajectoryEvaluationOptions& options) {
  TrajectoryEvaluation e;
  e.alignment = options.alignment;
  e.pairs = associate(estimate, reference, options.tolerance_s);
  if (e.pairs.t_s.size() < 3) {
    const auto range = [](const std::vector<io::StampedPose>& p) {
      if (p.empty()) return std::string("no poses");
      double lo = p.front().t_s, hi = lo;
      for (const auto& x : p) lo = std::min(lo, x.t_s), hi = std::max(hi, x.t_s);
      std::ostringstream text;
      text.precision(15);
      text << p.size() << " poses, t in [" << lo << ", " << hi << "] s";
      return text.str();
    };
    std::ostringstream text;
    text << "only " << e.pairs.t_s.size() << " poses associated within " << options.tolerance_s
         << " s, need at least 3 (estimate: " << range(estimate) << "; reference: " << range(reference)
         << "); check the timestamps' units or raise --tolerance";
    throw Error(text.str());
  }
  e.T_ref_est = alignPositions(e.pairs.estimate, e.pairs.reference, options.alignment);
  for (size_t i = 0; i < e.pairs.estimate.size(); ++i) {
    e.aligned.push_back(e.T_ref_est.apply(e.pairs.estimate[i]));
    e.errors_m.push_back((e.aligned.back() - e.pairs.reference[i]).norm());
  }
  const ErrorSummary s = summarize(e.errors_m);
  e.ate_rmse_m = s.rmse;
  e.ate_mean_m = s.mean;
  e.ate_median_m = s.median;
  e.ate_max_m = s.max;
  return e;
}

}  // namespace cenote::eval
