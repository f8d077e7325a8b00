// trajectory_alignment.h: absolute trajectory error (ATE) of an estimated trajectory against a
// reference, after aligning the estimate with Umeyama's method (1991) in sim(3) (rotation,
// translation and scale: monocular or COLMAP estimates) or se(3) (rotation and translation).
//   1. association: each estimate pose is paired with the reference pose nearest in time, within a
//      tolerance; pairs are taken in order of increasing time difference, each pose at most once.
//   2. alignment: T_ref_est = argmin sum_i |p_ref_i - (s R p_est_i + t)|^2 over camera positions.
//   3. ATE_i = |p_ref_i - (s R p_est_i + t)|; RMSE, mean, median and max over the pairs.
// Units: metres and seconds; poses are T_world_cam (camera centre = translation).
// Threads: free functions, independent.
#pragma once

#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "io/trajectory/tum_trajectory.h"

namespace cenote::eval {

enum class Alignment { kSim3, kSe3, kNone };

// "sim3", "se3" or "none". @throws cenote::Error otherwise.
Alignment parseAlignment(const std::string& name);
const char* toString(Alignment alignment);

// Camera positions of associated poses, in estimate time order.
struct AssociatedPositions {
  std::vector<double> t_s;                 // the estimate's timestamps
  std::vector<Eigen::Vector3d> estimate;   // p_world of the estimate, its own world frame
  std::vector<Eigen::Vector3d> reference;  // p_world of the reference
  size_t unmatched_estimate = 0, unmatched_reference = 0;
};

// @throws cenote::Error when tolerance_s is negative or not finite.
AssociatedPositions associate(const std::vector<io::StampedPose>& estimate, const std::vector<io::StampedPose>& reference,
                              double tolerance_s);

// p_ref = scale * R * p_est + t.
struct Similarity {
  double scale = 1.0;
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  Eigen::Vector3d apply(const Eigen::Vector3d& p) const { return scale * (R * p) + t; }
};

// Least-squares alignment of `estimate` onto `reference` (same length).
// @throws cenote::Error when fewer than 3 pairs are given, or for sim3 when the estimate
//         positions all coincide (no scale can be found).
Similarity alignPositions(const std::vector<Eigen::Vector3d>& estimate, const std::vector<Eigen::Vector3d>& reference,
                          Alignment alignment);

struct TrajectoryEvaluationOptions {
  Alignment alignment = Alignment::kSim3;
  double tolerance_s = 0.02;  // association: largest time difference of a pair
};

struct TrajectoryEvaluation {
  AssociatedPositions pairs;
  Alignment alignment = Alignment::kSim3;
  Similarity T_ref_est;
  std::vector<Eigen::Vector3d> aligned;  // T_ref_est applied to pairs.estimate
  std::vector<double> errors_m;          // ATE per pair
  double ate_rmse_m = 0.0, ate_mean_m = 0.0, ate_median_m = 0.0, ate_max_m = 0.0;
};

// @throws cenote::Error when fewer than 3 poses can be associated (naming how many each side has and
//         the time ranges), or as alignPositions.
TrajectoryEvaluation evaluateTrajectory(const std::vector<io::StampedPose>& estimate,
                                        const std::vector<io::StampedPose>& reference,
                                        const TrajectoryEvaluationOptions& options = {});

}  // namespace cenote::eval
