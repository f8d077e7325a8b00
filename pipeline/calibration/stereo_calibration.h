// stereo_calibration.h: a calibrated stereo rig, and the file formats it is read from.
//
// Conventions (OpenCV's stereoCalibrate / stereoRectify): R, T map points of the left camera
// to the right camera, p_right = R * p_left + T, with T in metres. Distortion is radial-tangential
// (k1, k2, p1, p2[, k3]).
// An already rectified rig (KITTI-style projection matrices) has `rectified` set and carries
// its geometry directly; it passes through the rectifier untouched.
#pragma once

#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "pipeline/frame/frames.h"

namespace cenote::pipeline {

struct CameraIntrinsics {
  cv::Matx33d K = cv::Matx33d::eye();
  std::vector<double> distortion;  // empty = none
};

struct StereoCalibration {
  cv::Size image_size;
  CameraIntrinsics left, right;
  cv::Matx33d R = cv::Matx33d::eye();
  cv::Vec3d T = {0.0, 0.0, 0.0};
  bool rectified = false;
  StereoGeometry rectified_geometry;  // only when rectified

  // @throws cenote::Error naming the first implausible value (non-positive focal length,
  // zero baseline, non-orthonormal R, empty size).
  void validate() const;
};

// OpenCV FileStorage YAML (the layout `cenote calibrate` writes):
//   image_width, image_height, K1, D1, K2, D2, R, T      (raw rig), or
//   image_width, image_height, P1, P2                    (rectified; baseline = -P2(0,3) / P2(0,0))
// M1/M2 are accepted for K1/K2 (OpenCV samples' names). @throws cenote::Error.
StereoCalibration readStereoCalibration(const std::string& path);

// Writes the raw-rig layout above. @throws cenote::Error.
void writeStereoCalibration(const std::string& path, const StereoCalibration& calibration);

// EuRoC / Kalibr-style `sensor.yaml` of each camera: intrinsics [fu, fv, cu, cv],
// distortion_coefficients (radial-tangential), resolution [w, h], T_BS (camera to body).
// @throws cenote::Error.
StereoCalibration readEurocSensorPair(const std::string& left_sensor_yaml, const std::string& right_sensor_yaml);

// Camera-to-body transform (T_BS) of one EuRoC sensor.yaml. @throws cenote::Error.
cv::Matx44d readEurocBodyFromSensor(const std::string& sensor_yaml);

// The reference paper's `intrinsics.yaml` (OpenCV FileStorage; pipeline/dataset/paper_dataset.h):
//   image_width, image_height; K1, D1 (left), K2, D2 (right) (also K_left, D_left, K_right, D_right);
//   baseline: the rig's baseline in millimetres; R, T (optional: identity and (-baseline, 0, 0))
//   mapping the left camera to the right, T in millimetres like the baseline (or in metres: T is
//   taken in the unit whose length matches the baseline within 1 %).
// @throws cenote::Error naming the file and key: missing keys, a T whose length matches the baseline
//         in neither unit, an invalid calibration.
StereoCalibration readPaperIntrinsics(const std::string& path);

// Any stereo calibration file cenote reads, recognised by its content; what `cenote stereo
// --calib` and `cenote-server --calibration` take:
//   KITTI calib.txt (rows "P0: ..."): rows P2 / P3 when its folder holds image_2 and image_3 (the
//     colour pair, as KittiDataset), else P0 / P1; the image size is that of the folder's first
//     left image, else `image_size`;
//   EuRoC / Kalibr sensor.yaml (T_BS, intrinsics): the left camera's, <mav0>/cam0/sensor.yaml,
//     read with its sibling <mav0>/cam1/sensor.yaml (readEurocSensorPair);
//   the paper's intrinsics.yaml (a FileStorage YAML with a `baseline` key: readPaperIntrinsics);
//   otherwise OpenCV FileStorage YAML (readStereoCalibration).
// @param image_size the size of the images to rectify, for a KITTI file beside no images (it has
//        no size of its own); empty: unknown.
// @throws cenote::Error naming the file, and for an unrecognised one the formats that are read.
StereoCalibration readCalibrationFile(const std::string& path, cv::Size image_size = {});

// KITTI `calib.txt` (rectified): rows "P0: 12 numbers" ...; `left`/`right` name the rows
// ("P0"/"P1" grey, "P2"/"P3" colour). @throws cenote::Error.
StereoCalibration readKittiCalibration(const std::string& path, const cv::Size& image_size, const std::string& left = "P0",
                                       const std::string& right = "P1");

}  // namespace cenote::pipeline
