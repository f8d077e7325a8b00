#include "eval/trajectory/trajectory_alignment.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "common/error.h"

namespace cenote::eval {
namespace {

using io::StampedPose;

// A non-planar loop with a changing orientation, 10 Hz.
std::vector<StampedPose> helix(int n, double t0 = 100.0) {
  std::vector<StampedPose> poses;
  for (int i = 0; i < n; ++i) {
    StampedPose p;
    p.t_s = t0 + 0.1 * i;
    const double a = 0.2 * i;
    p.T_world_cam.translation() = Eigen::Vector3d(3.0 * std::cos(a), 2.0 * std::sin(a), 0.05 * i);
    p.T_world_cam.linear() = Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    poses.push_back(p);
  }
  return poses;
}

// T * pose with T = scale * R, t, applied to the camera positions (and R to the orientations).
std::vector<StampedPose> transformed(const std::vector<StampedPose>& poses, double scale, const Eigen::Matrix3d& R,
                                     const Eigen::Vector3d& t) {
  std::vector<StampedPose> out = poses;
  for (auto& p : out) {
    p.T_world_cam.translation() = scale * (R * p.T_world_cam.translation()) + t;
    p.T_world_cam.linear() = R * p.T_world_cam.linear();
  }
  return out;
}

Eigen::Matrix3d someRotation() {
  return (Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(-0.4, Eigen::Vector3d::UnitX()) *
          Eigen::AngleAxisd(1.1, Eigen::Vector3d::UnitY()))
      .toRotationMatrix();
}

TEST(TrajectoryAlignment, FewerThanThreePairsIsAnErrorThatGivesTimeRanges) {
  const auto ref = helix(10);
  auto est = helix(2);
  try {
    evaluateTrajectory(est, ref);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("only 2 poses associated within 0.02 s"), std::string::npos) << e.what();
  }
  EXPECT_THROW(evaluateTrajectory(helix(10, 0.0), ref), Error);  // no overlap in time
}

TEST(TrajectoryAlignment, IdenticalTrajectoriesHaveZeroError) {
  const auto ref = helix(50);
  for (Alignment a : {Alignment::kSim3, Alignment::kSe3, Alignment::kNone}) {
    const TrajectoryEvaluation e = evaluateTrajectory(ref, ref, {a, 0.02});
    EXPECT_EQ(e.pairs.t_s.size(), 50u);
    EXPECT_NEAR(e.ate_rmse_m, 0.0, 1e-9) << toString(a);
    EXPECT_NEAR(e.ate_max_m, 0.0, 1e-9) << toString(a);
  }
}

TEST(TrajectoryAlignment, RotatedScaledTranslatedCopyAlignsBackInSim3NotSe3) {
  const auto ref = helix(60);
  const Eigen::Matrix3d R = someRotation();
  const auto est = transformed(ref, 0.37, R, Eigen::Vector3d(5.0, -2.0, 11.0));
  const TrajectoryEvaluation sim3 = evaluateTrajectory(est, ref, {Alignment::kSim3, 0.02});
  EXPECT_NEAR(sim3.ate_rmse_m, 0.0, 1e-9);
  EXPECT_NEAR(sim3.T_ref_est.scale, 1.0 / 0.37, 1e-9);
  EXPECT_TRUE(sim3.T_ref_est.R.isApprox(R.transpose(), 1e-9));
  const TrajectoryEvaluation se3 = evaluateTrajectory(est, ref, {Alignment::kSe3, 0.02});
  EXPECT_GT(se3.ate_rmse_m, 0.5);
  EXPECT_EQ(se3.T_ref_est.scale, 1.0);
  const TrajectoryEvaluation rigid = evaluateTrajectory(transformed(ref, 1.0, R, Eigen::Vector3d(1, 2, 3)), ref,
                                                        {Alignment::kSe3, 0.02});
  EXPECT_NEAR(rigid.ate_rmse_m, 0.0, 1e-9);
}

TEST(TrajectoryAlignment, HandComputedErrorsOfAKnownOffset) {
  // No alignment: errors are the offsets 0.3, 0.4, 0 and 1.2 -> RMSE sqrt((0.09+0.16+0+1.44)/4).
  auto ref = helix(4);
  auto est = ref;
  const double offsets[] = {0.3, 0.4, 0.0, 1.2};
  for (int i = 0; i < 4; ++i) est[i].T_world_cam.translation().x() += offsets[i];
  const TrajectoryEvaluation e = evaluateTrajectory(est, ref, {Alignment::kNone, 0.02});
  EXPECT_NEAR(e.ate_rmse_m, std::sqrt(1.69 / 4.0), 1e-12);
  EXPECT_NEAR(e.ate_mean_m, 1.9 / 4.0, 1e-12);
  EXPECT_NEAR(e.ate_median_m, 0.35, 1e-12);
  EXPECT_NEAR(e.ate_max_m, 1.2, 1e-12);
}

TEST(TrajectoryAlignment, AssociationIsNearestWithinToleranceAndOneToOne) {
  const auto ref = helix(10);  // 100.0, 100.1, ...
  std::vector<StampedPose> est = {ref[0], ref[1], ref[1], ref[5]};
  est[0].t_s = 100.004;  // near 100.0
  est[1].t_s = 100.09;   // near 100.1 (0.01 away)
  est[2].t_s = 100.105;  // also near 100.1 (0.005 away): wins it
  est[3].t_s = 100.53;   // 0.03 from 100.5: beyond 0.02
  const AssociatedPositions pairs = associate(est, ref, 0.02);
  ASSERT_EQ(pairs.t_s.size(), 2u);
  EXPECT_DOUBLE_EQ(pairs.t_s[0], 100.004);
  EXPECT_DOUBLE_EQ(pairs.t_s[1], 100.105);
  EXPECT_EQ(pairs.unmatched_estimate, 2u);
  EXPECT_EQ(pairs.unmatched_reference, 8u);
  EXPECT_THROW(associate(est, ref, -1.0), Error);
}

TEST(TrajectoryAlignment, NoisyCopyAlignsToTheNoiseLevel) {
  const auto ref = helix(200);
  auto est = transformed(ref, 2.0, someRotation(), Eigen::Vector3d(1, 1, 1));
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 0.01);
  for (auto& p : est) p.T_world_cam.translation() += Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
  const TrajectoryEvaluation e = evaluateTrajectory(est, ref);
  // 0.01 per axis in the estimate's units is 0.005 m per axis after scaling by 1/2: sqrt(3) * 0.005.
  EXPECT_NEAR(e.ate_rmse_m, std::sqrt(3.0) * 0.005, 0.002);
}

TEST(TrajectoryAlignment, CoincidentPositionsCannotBeScaled) {
  auto ref = helix(5);
  auto est = ref;
  for (auto& p : est) p.T_world_cam.translation().setZero();
  EXPECT_THROW(evaluateTrajectory(est, ref, {Alignment::kSim3, 0.02}), Error);
  EXPECT_THROW(parseAlignment("affine"), Error);
}

}  // namespace
}  // namespace cenote::eval
