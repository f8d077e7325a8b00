#include "pipeline/frame/frame_admission.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <opencv2/calib3d.hpp>
#include <string>
#include <tuple>
#include <vector>

#include "common/error.h"
#include "tests/support/raw_rig.h"

namespace cenote::pipeline {
namespace {

// A raw rig whose rectification turns the left camera by a visible amount (R1 far from identity).
StereoCalibration tiltedRig() {
  return test::rawRig(cv::Size(64, 48), {cv::Matx33d(50, 0, 32, 0, 51, 24, 0, 0, 1), {-0.1, 0.02, 0.001, -0.0005}},
                      {cv::Matx33d(52, 0, 31, 0, 52, 23, 0, 0, 1), {-0.09, 0.01, -0.0008, 0.0003}},
                      cv::Vec3d(0.02, -0.04, 0.01), cv::Vec3d(-0.12, 0.004, 0.003));
}

RunConfig keyframesAt(double translation_m, double rotation_deg) {
  RunConfig run;
  run.keyframe_translation_m = translation_m;
  run.keyframe_rotation_deg = rotation_deg;
  return run;
}

Eigen::Isometry3d at(double x_m, double yaw_deg = 0.0) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(yaw_deg * M_PI / 180.0, Eigen::Vector3d::UnitY()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(x_m, 0.2, -0.1);
  return T;
}

PoseLookup always(const Eigen::Isometry3d& T) {
  return [T](double) { return std::optional<Eigen::Isometry3d>(T); };
}

StereoFrame texturedFrame(const cv::Size& size, double t_s) {
  StereoFrame frame;
  frame.t_s = t_s;
  frame.left = cv::Mat(size, CV_8UC1);
  frame.right = cv::Mat(size, CV_8UC1);
  cv::RNG rng(7);
  rng.fill(frame.left, cv::RNG::UNIFORM, 0, 256);
  rng.fill(frame.right, cv::RNG::UNIFORM, 0, 256);
  return frame;
}

// Keyframe choice on a tilted rig: its rectifier, a textured frame of its size, and the admission.
struct Keyframes {
  Keyframes(double translation_m, double rotation_deg) : admission(rectifier, keyframesAt(translation_m, rotation_deg)) {}
  Admission decide(double t_s, const Eigen::Isometry3d& T_world_raw) {
    return admission.decide(t_s, always(T_world_raw)).admission;
  }
  // Decides the frame at t_s with the pose T_world_raw, which must be admitted, and admits its images.
  void admitKeyframe(double t_s, const Eigen::Isometry3d& T_world_raw) {
    const FrameDecision d = admission.decide(t_s, always(T_world_raw));
    ASSERT_EQ(d.admission, Admission::kAdmitted) << "t = " << t_s;
    admission.admit(frame, d.T_world_raw);
  }

  const Rectifier rectifier{tiltedRig()};
  const StereoFrame frame = texturedFrame(rectifier.geometry().image_size, 0.0);
  FrameAdmission admission;
};

TEST(FrameAdmission, FirstFrameWithAPoseIsAdmittedWithThatPose) {
  const Rectifier rectifier(tiltedRig());
  FrameAdmission admission(rectifier, RunConfig{});
  EXPECT_EQ(admission.lastTimestamp(), -std::numeric_limits<double>::infinity());
  const FrameDecision d = admission.decide(1.0, always(at(0.5, 10.0)));
  EXPECT_EQ(d.admission, Admission::kAdmitted);
  EXPECT_TRUE(d.T_world_raw.isApprox(at(0.5, 10.0), 0.0));
  EXPECT_EQ(admission.lastTimestamp(), 1.0);
}

TEST(FrameAdmission, OutOfOrderAndNonFiniteTimestampsAreRefusedAndDoNotMoveTheTime) {
  const Rectifier rectifier(tiltedRig());
  FrameAdmission admission(rectifier, RunConfig{});
  ASSERT_EQ(admission.decide(2.0, always(at(0.0))).admission, Admission::kAdmitted);
  for (const double t_s : {2.0, 1.5, -1.0, std::numeric_limits<double>::quiet_NaN(),
                           std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()}) {
    EXPECT_EQ(admission.decide(t_s, always(at(0.0))).admission, Admission::kOutOfOrder) << "t = " << t_s;
    EXPECT_EQ(admission.lastTimestamp(), 2.0) << "after t = " << t_s;
  }
  // The time did not move: a frame just after the last admitted one still goes on.
  EXPECT_EQ(admission.decide(2.001, always(at(0.0))).admission, Admission::kAdmitted);
  EXPECT_EQ(admission.lastTimestamp(), 2.001);
}

TEST(FrameAdmission, NonFiniteFirstTimestampIsOutOfOrder) {
  const Rectifier rectifier(tiltedRig());
  FrameAdmission admission(rectifier, RunConfig{});
  EXPECT_EQ(admission.decide(std::numeric_limits<double>::quiet_NaN(), always(at(0.0))).admission, Admission::kOutOfOrder);
  EXPECT_EQ(admission.decide(-std::numeric_limits<double>::infinity(), always(at(0.0))).admission, Admission::kOutOfOrder);
  // +inf would come after anything, and then nothing could come after it.
  EXPECT_EQ(admission.decide(std::numeric_limits<double>::infinity(), always(at(0.0))).admission, Admission::kOutOfOrder);
  EXPECT_EQ(admission.lastTimestamp(), -std::numeric_limits<double>::infinity());
  EXPECT_EQ(admission.decide(0.0, always(at(0.0))).admission, Admission::kAdmitted);
}

TEST(FrameAdmission, PoseLookupIsNotAskedForAFrameOutOfOrder) {
  const Rectifier rectifier(tiltedRig());
  FrameAdmission admission(rectifier, RunConfig{});
  std::vector<double> asked;
  const PoseLookup counting = [&asked](double t_s) {
    asked.push_back(t_s);
    return std::optional<Eigen::Isometry3d>(at(0.0));
  };
  // Positive control: the lookup is asked for a frame in time order, with its timestamp.
  ASSERT_EQ(admission.decide(3.0, counting).admission, Admission::kAdmitted);
  ASSERT_EQ(asked, std::vector<double>{3.0});
  EXPECT_EQ(admission.decide(3.0, counting).admission, Admission::kOutOfOrder);
  EXPECT_EQ(admission.decide(2.0, counting).admission, Admission::kOutOfOrder);
  EXPECT_EQ(admission.decide(std::numeric_limits<double>::quiet_NaN(), counting).admission, Admission::kOutOfOrder);
  EXPECT_EQ(asked, std::vector<double>{3.0});
}

TEST(FrameAdmission, NoPoseIsRefusedButSetsTheTime) {
  const Rectifier rectifier(tiltedRig());
  FrameAdmission admission(rectifier, RunConfig{});
  const PoseLookup none = [](double) { return std::optional<Eigen::Isometry3d>(); };
  EXPECT_EQ(admission.decide(1.0, none).admission, Admission::kNoPose);
  EXPECT_EQ(admission.lastTimestamp(), 1.0);
  EXPECT_EQ(admission.decide(1.0, always(at(0.0))).admission, Admission::kOutOfOrder);
  EXPECT_EQ(admission.decide(1.1, always(at(0.0))).admission, Admission::kAdmitted);
}

TEST(FrameAdmission, TranslationThresholdIsMeasuredFromTheLastAdmittedFrame) {
  Keyframes k(0.5, 0.0);
  k.admitKeyframe(1.0, at(0.0));
  EXPECT_EQ(k.decide(2.0, at(0.3)), Admission::kNotKeyframe);
  EXPECT_EQ(k.decide(3.0, at(0.49)), Admission::kNotKeyframe);
  // 0.6 m from the admitted frame at 0; (0.3 and 0.49 were never admitted, so not 0.11 m from 0.49).
  k.admitKeyframe(4.0, at(0.6));
  EXPECT_EQ(k.decide(5.0, at(1.0)), Admission::kNotKeyframe);
  EXPECT_EQ(k.decide(6.0, at(1.2)), Admission::kAdmitted);
}

TEST(FrameAdmission, RotationThresholdIsMeasuredFromTheLastAdmittedFrame) {
  Keyframes k(0.0, 10.0);
  k.admitKeyframe(1.0, at(0.0, 0.0));
  // Translation is not a threshold here: 5 m of travel alone does not make a keyframe.
  EXPECT_EQ(k.decide(2.0, at(5.0, 6.0)), Admission::kNotKeyframe);
  k.admitKeyframe(3.0, at(0.0, 11.0));
  EXPECT_EQ(k.decide(4.0, at(0.0, 20.0)), Admission::kNotKeyframe);
  EXPECT_EQ(k.decide(5.0, at(0.0, 21.5)), Admission::kAdmitted);
}

TEST(FrameAdmission, DecidedButNeverAdmittedFrameIsNotTheKeyframeReference) {
  Keyframes k(0.5, 0.0);
  k.admitKeyframe(1.0, at(0.0));
  // Admitted by decide() at 1 m but its images never arrive (admit() is not called).
  ASSERT_EQ(k.decide(2.0, at(1.0)), Admission::kAdmitted);
  // 1.2 m is 0.2 m from the frame at 1 m but 1.2 m from the last admitted one at 0: a keyframe.
  EXPECT_EQ(k.decide(3.0, at(1.2)), Admission::kAdmitted);
  // Positive control: once a frame at 1.2 m is admitted, 1.4 m is too close.
  k.admission.admit(k.frame, at(1.2));
  EXPECT_EQ(k.decide(4.0, at(1.4)), Admission::kNotKeyframe);
}

TEST(FrameAdmission, FailedAdmitDoesNotBecomeTheKeyframeReference) {
  const Rectifier rectifier(tiltedRig());
  const StereoFrame frame = texturedFrame(rectifier.geometry().image_size, 0.0);
  FrameAdmission admission(rectifier, keyframesAt(0.5, 0.0));
  admission.admit(frame, at(0.0));
  ASSERT_EQ(admission.decide(1.0, always(at(1.0))).admission, Admission::kAdmitted);
  StereoFrame empty;
  EXPECT_THROW(admission.admit(empty, at(1.0)), Error);
  EXPECT_EQ(admission.decide(2.0, always(at(1.2))).admission, Admission::kAdmitted);
}

TEST(FrameAdmission, AdmitPosesTheRectifiedCameraFromStereoRectifyR1) {
  const StereoCalibration c = tiltedRig();
  const Rectifier rectifier(c);
  // Independent of the rectifier: R1 straight from OpenCV, with the rectifier's settings.
  cv::Mat R1, R2, P1, P2, Q;
  cv::stereoRectify(cv::Mat(c.left.K), cv::Mat(c.left.distortion, true), cv::Mat(c.right.K),
                    cv::Mat(c.right.distortion, true), c.image_size, cv::Mat(c.R), cv::Mat(c.T), R1, R2, P1, P2, Q,
                    cv::CALIB_ZERO_DISPARITY, 0.0, c.image_size);
  Eigen::Matrix3d R1_e;
  for (int r = 0; r < 3; ++r) {
    for (int col = 0; col < 3; ++col) R1_e(r, col) = R1.at<double>(r, col);
  }
  // Premise: the rectification turns the camera, so a missing or transposed R1 would show.
  ASSERT_GT((R1_e - Eigen::Matrix3d::Identity()).norm(), 1e-3);
  ASSERT_GT((R1_e - R1_e.transpose()).norm(), 1e-3);

  // p_rect = R1 p_raw: the rectified camera in the raw one is the rotation R1^T, no translation.
  Eigen::Isometry3d T_raw_rect = Eigen::Isometry3d::Identity();
  T_raw_rect.linear() = R1_e.transpose();
  EXPECT_TRUE(rectifiedFromRaw(rectifier).isApprox(T_raw_rect, 0.0)) << rectifiedFromRaw(rectifier).matrix();

  const Eigen::Isometry3d T_world_raw = at(0.7, 25.0);
  FrameAdmission admission(rectifier, RunConfig{});
  const StereoFrame frame = texturedFrame(c.image_size, 4.25);
  const FrameDecision d = admission.decide(frame.t_s, always(T_world_raw));
  ASSERT_EQ(d.admission, Admission::kAdmitted);
  const PosedPair posed = admission.admit(frame, d.T_world_raw);
  const Eigen::Isometry3d expected = T_world_raw * T_raw_rect;
  EXPECT_TRUE(posed.T_world_cam.isApprox(expected, 1e-15)) << "got\n"
                                                           << posed.T_world_cam.matrix() << "\nexpected\n"
                                                           << expected.matrix();
  // A point on the rectified optical axis lands where R1 says in the world.
  const Eigen::Vector3d p_rect(0.0, 0.0, 2.0);
  const Eigen::Vector3d p_raw = R1_e.transpose() * p_rect;
  EXPECT_LT((posed.T_world_cam * p_rect - T_world_raw * p_raw).norm(), 1e-12);
}

TEST(FrameAdmission, AdmittedImagesAreTheRectifiersBitForBit) {
  const Rectifier rectifier(tiltedRig());
  ASSERT_FALSE(rectifier.isPassthrough());
  FrameAdmission admission(rectifier, RunConfig{});
  const StereoFrame frame = texturedFrame(rectifier.geometry().image_size, 1.5);
  const RectifiedPair direct = rectifier.rectify(frame);
  const PosedPair posed = admission.admit(frame, at(0.0));
  EXPECT_EQ(posed.pair.t_s, 1.5);
  EXPECT_EQ(posed.pair.geometry.fx, direct.geometry.fx);
  EXPECT_EQ(posed.pair.geometry.baseline_m, direct.geometry.baseline_m);
  for (const auto& [got, want, which] :
       {std::tuple{&posed.pair.left, &direct.left, "left"}, std::tuple{&posed.pair.right, &direct.right, "right"}}) {
    // Premise: non-empty images, mostly valid pixels, and not the raw image passed through.
    ASSERT_EQ(want->size(), frame.left.size()) << which;
    ASSERT_GT(cv::countNonZero(*want), want->rows * want->cols / 2) << which;
    ASSERT_GT(cv::norm(*want, which == std::string("left") ? frame.left : frame.right, cv::NORM_INF), 0.0) << which;
    ASSERT_EQ(got->size(), want->size()) << which;
    ASSERT_EQ(got->type(), want->type()) << which;
    EXPECT_EQ(cv::norm(*got, *want, cv::NORM_INF), 0.0) << which << " image differs from Rectifier::rectify";
  }
}

}  // namespace
}  // namespace cenote::pipeline
