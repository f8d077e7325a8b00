#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "common/error.h"
#include "tests/support/error_message.h"
#include "tests/support/raw_rig.h"
#include "pipeline/calibration/rectifier.h"
#include "pipeline/calibration/stereo_calibration.h"

namespace cenote::pipeline {
namespace {

std::string temp(const std::string& name) { return testing::TempDir() + "/" + name; }

StereoCalibration exampleRig() {
  return test::rawRig(cv::Size(640, 480), {cv::Matx33d(500, 0, 320, 0, 502, 241, 0, 0, 1), {-0.12, 0.03, 0.001, -0.0005}},
                      {cv::Matx33d(505, 0, 318, 0, 506, 238, 0, 0, 1), {-0.11, 0.02, -0.0008, 0.0003}},
                      cv::Vec3d(0.01, -0.02, 0.005), cv::Vec3d(-0.12, 0.002, 0.001));
}

TEST(StereoCalibration, WrittenAndReadBackGivesTheSameRig) {
  const StereoCalibration c = exampleRig();
  writeStereoCalibration(temp("rig.yaml"), c);
  const StereoCalibration back = readStereoCalibration(temp("rig.yaml"));
  EXPECT_EQ(back.image_size, c.image_size);
  EXPECT_LT(cv::norm(back.left.K - c.left.K), 1e-12);
  EXPECT_LT(cv::norm(back.R - c.R), 1e-12);
  EXPECT_LT(cv::norm(back.T - c.T), 1e-12);
  EXPECT_EQ(back.right.distortion, c.right.distortion);
  EXPECT_FALSE(back.rectified);
}

TEST(StereoCalibration, RectifiedLayoutGivesBaselineFromProjectionMatrices) {
  std::ofstream(temp("rect.yaml")) << "%YAML:1.0\nimage_width: 1241\nimage_height: 376\n"
                                      "P1: !!opencv-matrix\n  rows: 3\n  cols: 4\n  dt: d\n"
                                      "  data: [718.856, 0, 607.1928, 0, 0, 718.856, 185.2157, 0, 0, 0, 1, 0]\n"
                                      "P2: !!opencv-matrix\n  rows: 3\n  cols: 4\n  dt: d\n"
                                      "  data: [718.856, 0, 607.1928, -386.1448, 0, 718.856, 185.2157, 0, 0, 0, 1, 0]\n";
  const StereoCalibration c = readStereoCalibration(temp("rect.yaml"));
  ASSERT_TRUE(c.rectified);
  EXPECT_NEAR(c.rectified_geometry.baseline_m, 386.1448 / 718.856, 1e-12);
  EXPECT_DOUBLE_EQ(c.rectified_geometry.cx, 607.1928);
}

TEST(StereoCalibration, MissingMatrixAndNonRotationAreErrorsNamingTheFile) {
  std::ofstream(temp("bad.yaml")) << "%YAML:1.0\nimage_width: 640\nimage_height: 480\n"
                                     "K1: !!opencv-matrix\n  rows: 3\n  cols: 3\n  dt: d\n"
                                     "  data: [500, 0, 320, 0, 500, 240, 0, 0, 1]\n";
  try {
    readStereoCalibration(temp("bad.yaml"));
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("bad.yaml: missing K2"), std::string::npos) << e.what();
  }
  StereoCalibration c = exampleRig();
  c.R = cv::Matx33d(1, 0, 0, 0, 2, 0, 0, 0, 1);
  writeStereoCalibration(temp("scaled.yaml"), c);
  try {
    readStereoCalibration(temp("scaled.yaml"));
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("R is not a rotation matrix"), std::string::npos) << e.what();
  }
  EXPECT_THROW(readStereoCalibration(temp("absent.yaml")), Error);
}

// EuRoC MH_01 cam0/cam1 sensor.yaml values.
void writeEurocSensor(const std::string& path, const std::string& T_BS, const std::string& intrinsics,
                      const std::string& distortion) {
  std::ofstream(path) << "%YAML:1.0\nsensor_type: camera\ncomment: VI-Sensor\nT_BS:\n  cols: 4\n  rows: 4\n"
                      << "  data: [" << T_BS << "]\nrate_hz: 20\nresolution: [752, 480]\n"
                      << "camera_model: pinhole\nintrinsics: [" << intrinsics << "] #fu, fv, cu, cv\n"
                      << "distortion_model: radial-tangential\ndistortion_coefficients: [" << distortion << "]\n";
}

TEST(StereoCalibration, EurocSensorPairGivesTheRigBetweenTheCameras) {
  writeEurocSensor(temp("cam0.yaml"),
                   "0.0148655429818, -0.999880929698, 0.00414029679422, -0.0216401454975, "
                   "0.999557249008, 0.0149672133247, 0.025715529948, -0.064676986768, "
                   "-0.0257744366974, 0.00375618835797, 0.999660727178, 0.00981073058949, 0.0, 0.0, 0.0, 1.0",
                   "458.654, 457.296, 367.215, 248.375", "-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05");
  writeEurocSensor(temp("cam1.yaml"),
                   "0.0125552670891, -0.999755099723, 0.0182237714554, -0.0198435579556, "
                   "0.999598781151, 0.0130119051815, 0.0251588363115, 0.0453689425024, "
                   "-0.0253898008918, 0.0179005838253, 0.999517347078, 0.00786212447038, 0.0, 0.0, 0.0, 1.0",
                   "457.587, 456.134, 379.999, 255.238", "-0.28368365, 0.07451284, -0.00010473, -3.55590700e-05");
  const StereoCalibration c = readEurocSensorPair(temp("cam0.yaml"), temp("cam1.yaml"));
  EXPECT_EQ(c.image_size, cv::Size(752, 480));
  EXPECT_DOUBLE_EQ(c.left.K(0, 0), 458.654);
  EXPECT_DOUBLE_EQ(c.right.K(1, 2), 255.238);
  ASSERT_EQ(c.left.distortion.size(), 4u);
  // The published MH_01 baseline is 0.110 m, along the right camera's -x.
  EXPECT_NEAR(cv::norm(c.T), 0.1101, 5e-4);
  EXPECT_LT(c.T[0], -0.109);
  const Rectifier rectifier(c);
  EXPECT_NEAR(rectifier.geometry().baseline_m, 0.1101, 5e-4);
}

TEST(StereoCalibration, KittiCalibTxtRowsGiveRectifiedGeometry) {
  std::ofstream(temp("calib.txt"))
      << "P0: 7.188560e+02 0.000000e+00 6.071928e+02 0.000000e+00 0.000000e+00 7.188560e+02 1.852157e+02 "
         "0.000000e+00 0.000000e+00 0.000000e+00 1.000000e+00 0.000000e+00\n"
      << "P1: 7.188560e+02 0.000000e+00 6.071928e+02 -3.861448e+02 0.000000e+00 7.188560e+02 1.852157e+02 "
         "0.000000e+00 0.000000e+00 0.000000e+00 1.000000e+00 0.000000e+00\n";
  const StereoCalibration c = readKittiCalibration(temp("calib.txt"), cv::Size(1241, 376));
  EXPECT_TRUE(c.rectified);
  EXPECT_NEAR(c.rectified_geometry.baseline_m, 0.537165, 1e-5);
  EXPECT_THROW(readKittiCalibration(temp("calib.txt"), cv::Size(1241, 376), "P2", "P3"), Error);
}

// readCalibrationFile: each layout the runner reads, from a file alone, as `cenote stereo --calib`
// and `cenote-server --calibration` take it.
const char* kKittiCalib00 =
    "P0: 7.188560000000e+02 0.000000000000e+00 6.071928000000e+02 0.000000000000e+00 0.000000000000e+00 "
    "7.188560000000e+02 1.852157000000e+02 0.000000000000e+00 0.000000000000e+00 0.000000000000e+00 "
    "1.000000000000e+00 0.000000000000e+00\n"
    "P1: 7.188560000000e+02 0.000000000000e+00 6.071928000000e+02 -3.861448000000e+02 0.000000000000e+00 "
    "7.188560000000e+02 1.852157000000e+02 0.000000000000e+00 0.000000000000e+00 0.000000000000e+00 "
    "1.000000000000e+00 0.000000000000e+00\n"
    "P2: 7.188560000000e+02 0.000000000000e+00 6.071928000000e+02 4.538225000000e+01 0.000000000000e+00 "
    "7.188560000000e+02 1.852157000000e+02 -1.130887000000e-01 0.000000000000e+00 0.000000000000e+00 "
    "1.000000000000e+00 3.779761000000e-03\n"
    "P3: 7.188560000000e+02 0.000000000000e+00 6.071928000000e+02 -3.372877000000e+02 0.000000000000e+00 "
    "7.188560000000e+02 1.852157000000e+02 2.369057000000e+00 0.000000000000e+00 0.000000000000e+00 "
    "1.000000000000e+00 4.915215000000e-03\n"
    "Tr: 4.276802385584e-04 -9.999672484946e-01 -8.084491683471e-03 -1.198459927713e-02 -7.210626507497e-03 "
    "8.081198471645e-03 -9.999413164504e-01 -5.403984729748e-02 9.999738645903e-01 4.859485810390e-04 "
    "-7.206933692422e-03 -2.921968648686e-01\n";

std::string freshDir(const std::string& name) {
  const std::string dir = temp(name);
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

TEST(CalibrationFile, OpenCvYamlIsReadAsBeforeIncludingItsRectifiedP1P2Layout) {
  writeStereoCalibration(temp("any_rig.yaml"), exampleRig());
  const StereoCalibration c = readCalibrationFile(temp("any_rig.yaml"));
  EXPECT_EQ(c.image_size, cv::Size(640, 480));
  EXPECT_LT(cv::norm(c.T - exampleRig().T), 1e-12);
  std::ofstream(temp("any_rect.yaml"))
      << "%YAML:1.0\nimage_width: 1241\nimage_height: 376\n"
         "P1: !!opencv-matrix\n  rows: 3\n  cols: 4\n  dt: d\n"
         "  data: [718.856, 0, 607.1928, 0, 0, 718.856, 185.2157, 0, 0, 0, 1, 0]\n"
         "P2: !!opencv-matrix\n  rows: 3\n  cols: 4\n  dt: d\n"
         "  data: [718.856, 0, 607.1928, -386.1448, 0, 718.856, 185.2157, 0, 0, 0, 1, 0]\n";
  EXPECT_NEAR(readCalibrationFile(temp("any_rect.yaml")).rectified_geometry.baseline_m, 386.1448 / 718.856, 1e-12);
}

TEST(CalibrationFile, EurocCam0SensorYamlIsReadWithItsCam1Sibling) {
  const std::string mav0 = freshDir("calib_euroc/mav0");
  std::filesystem::create_directories(mav0 + "/cam0");
  std::filesystem::create_directories(mav0 + "/cam1");
  writeEurocSensor(mav0 + "/cam0/sensor.yaml",
                   "0.0148655429818, -0.999880929698, 0.00414029679422, -0.0216401454975, "
                   "0.999557249008, 0.0149672133247, 0.025715529948, -0.064676986768, "
                   "-0.0257744366974, 0.00375618835797, 0.999660727178, 0.00981073058949, 0.0, 0.0, 0.0, 1.0",
                   "458.654, 457.296, 367.215, 248.375", "-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05");
  const std::string cam0 = mav0 + "/cam0/sensor.yaml", cam1 = mav0 + "/cam1/sensor.yaml";
  EXPECT_EQ(cenote::test::errorMessage([&] { readCalibrationFile(cam0); }),
            cam0 + ": the right camera's " + cam1 + " is missing (an EuRoC / Kalibr sensor.yaml describes one camera)")
      << "one camera's sensor.yaml was read as a stereo rig";
  writeEurocSensor(cam1,
                   "0.0125552670891, -0.999755099723, 0.0182237714554, -0.0198435579556, "
                   "0.999598781151, 0.0130119051815, 0.0251588363115, 0.0453689425024, "
                   "-0.0253898008918, 0.0179005838253, 0.999517347078, 0.00786212447038, 0.0, 0.0, 0.0, 1.0",
                   "457.587, 456.134, 379.999, 255.238", "-0.28368365, 0.07451284, -0.00010473, -3.55590700e-05");
  const StereoCalibration c = readCalibrationFile(cam0);
  EXPECT_EQ(c.image_size, cv::Size(752, 480));
  EXPECT_DOUBLE_EQ(c.right.K(1, 2), 255.238);
  EXPECT_NEAR(cv::norm(c.T), 0.1101, 5e-4);  // MH_01's published baseline
  EXPECT_EQ(cenote::test::errorMessage([&] { readCalibrationFile(cam1); }),
            cam1 + ": an EuRoC / Kalibr sensor.yaml describes one camera; give the left camera's, "
                   "<mav0>/cam0/sensor.yaml, with cam1/sensor.yaml beside it")
      << "the right camera's file was taken as the left";
}

TEST(CalibrationFile, KittiCalibTxtTakesTheColourRowsAndImageSizeOfItsSequence) {
  const std::string seq = freshDir("calib_kitti/00");
  std::ofstream(seq + "/calib.txt") << kKittiCalib00;
  // Alone: no image size of its own.
  EXPECT_EQ(cenote::test::errorMessage([&] { readCalibrationFile(seq + "/calib.txt"); }),
            seq + "/calib.txt: a KITTI calib.txt has no image size, and there is no " + seq +
                "/image_0/000000.png beside it to take it from")
      << "a KITTI calib.txt without an image size was read";
  // Alone with the size of the images: the grey pair P0 / P1, baseline 386.1448 / 718.856 m.
  const StereoCalibration grey = readCalibrationFile(seq + "/calib.txt", cv::Size(1241, 376));
  EXPECT_TRUE(grey.rectified);
  EXPECT_NEAR(grey.rectified_geometry.baseline_m, 0.537165, 1e-6);
  // In its sequence folder with image_2 / image_3: the colour pair P2 / P3, the images' size.
  std::filesystem::create_directories(seq + "/image_2");
  std::filesystem::create_directories(seq + "/image_3");
  cv::imwrite(seq + "/image_2/000000.png", cv::Mat(376, 1241, CV_8UC3, cv::Scalar(1, 2, 3)));
  const StereoCalibration colour = readCalibrationFile(seq + "/calib.txt");
  EXPECT_EQ(colour.image_size, cv::Size(1241, 376));
  EXPECT_NEAR(colour.rectified_geometry.baseline_m, (45.38225 + 337.2877) / 718.856, 1e-6);
}

TEST(CalibrationFile, UnrecognisedFileSaysWhichLayoutsAreRead) {
  std::ofstream(temp("notes.txt")) << "left camera: 500 px\n";
  try {
    readCalibrationFile(temp("notes.txt"));
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(" (calibration files read: OpenCV stereo YAML with image_width, "
                                         "image_height, K1 D1 K2 D2 R T or P1 P2; EuRoC / Kalibr cam0/sensor.yaml "
                                         "beside cam1/sensor.yaml; KITTI calib.txt)"),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(cenote::test::errorMessage([&] { readCalibrationFile(temp("absent.yaml")); }),
            "calibration file not found: " + temp("absent.yaml"));
}

// Draws a small bright blob at a sub-pixel position.
void drawBlob(cv::Mat& image, cv::Point2d at) {
  for (int y = 0; y < image.rows; ++y)
    for (int x = 0; x < image.cols; ++x) {
      const double r2 = (x - at.x) * (x - at.x) + (y - at.y) * (y - at.y);
      image.at<uint8_t>(y, x) = cv::saturate_cast<uint8_t>(image.at<uint8_t>(y, x) + 250.0 * std::exp(-r2 / 8.0));
    }
}

cv::Point2d centroid(const cv::Mat& image) {
  const cv::Moments m = cv::moments(image > 60, true);
  return {m.m10 / m.m00, m.m01 / m.m00};
}

TEST(Rectifier, PointsLandOnTheSameRowWithTheDisparityOfTheirDepth) {
  const StereoCalibration c = exampleRig();
  const Rectifier rectifier(c);
  for (const cv::Point3d p_left : {cv::Point3d(0.3, -0.2, 2.0), cv::Point3d(-0.5, 0.4, 3.5), cv::Point3d(0.0, 0.0, 1.5)}) {
    std::vector<cv::Point2d> in_left, in_right;
    cv::projectPoints(std::vector<cv::Point3d>{p_left}, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), cv::Mat(c.left.K),
                      cv::Mat(c.left.distortion), in_left);
    cv::Mat rvec;
    cv::Rodrigues(cv::Mat(c.R), rvec);
    cv::projectPoints(std::vector<cv::Point3d>{p_left}, rvec, cv::Mat(c.T), cv::Mat(c.right.K), cv::Mat(c.right.distortion),
                      in_right);
    StereoFrame frame;
    frame.left = cv::Mat(c.image_size, CV_8UC1, cv::Scalar(0));
    frame.right = frame.left.clone();
    drawBlob(frame.left, in_left[0]);
    drawBlob(frame.right, in_right[0]);
    const RectifiedPair pair = rectifier.rectify(frame);
    const cv::Point2d l = centroid(pair.left), r = centroid(pair.right);
    EXPECT_NEAR(l.y, r.y, 0.3) << "rows differ for point " << p_left;
    // Depth along the rectified left optical axis.
    const cv::Vec3d p_rect = rectifier.R_rect_left() * cv::Vec3d(p_left.x, p_left.y, p_left.z);
    const double expected = rectifier.geometry().fx * rectifier.geometry().baseline_m / p_rect[2];
    EXPECT_NEAR(l.x - r.x, expected, 0.3) << "disparity for point " << p_left;
  }
}

TEST(Rectifier, RejectsImagesOfAnotherSize) {
  const Rectifier rectifier(exampleRig());
  StereoFrame frame;
  frame.left = cv::Mat(480, 640, CV_8UC1, cv::Scalar(0));
  frame.right = cv::Mat(479, 640, CV_8UC1, cv::Scalar(0));
  EXPECT_EQ(cenote::test::errorMessage([&] { rectifier.rectify(frame); }),
            "rectifier: right image is 640x479 but the calibration is for 640x480");
}

TEST(Rectifier, RectifiedCalibrationPassesImagesThrough) {
  StereoCalibration c;
  c.image_size = cv::Size(8, 4);
  c.rectified = true;
  c.rectified_geometry = {100, 100, 4, 2, 0.1, c.image_size};
  const Rectifier rectifier(c);
  StereoFrame frame;
  frame.left = cv::Mat(4, 8, CV_8UC1, cv::Scalar(7));
  frame.right = cv::Mat(4, 8, CV_8UC1, cv::Scalar(9));
  const RectifiedPair pair = rectifier.rectify(frame);
  EXPECT_TRUE(rectifier.isPassthrough());
  EXPECT_EQ(pair.left.data, frame.left.data);
  EXPECT_DOUBLE_EQ(pair.geometry.baseline_m, 0.1);
}

// cv::remap of `frame`'s images with OpenCV's own fixed-point maps of `c` (stereoRectify,
// initUndistortRectifyMap to CV_16SC2): what Rectifier::rectify must return, pixel for pixel.
std::pair<cv::Mat, cv::Mat> remapWithOpenCv(const StereoCalibration& c, const StereoFrame& frame) {
  cv::Mat R1, R2, P1, P2, Q;
  cv::stereoRectify(cv::Mat(c.left.K), cv::Mat(c.left.distortion), cv::Mat(c.right.K), cv::Mat(c.right.distortion),
                    c.image_size, cv::Mat(c.R), cv::Mat(c.T), R1, R2, P1, P2, Q, cv::CALIB_ZERO_DISPARITY, 0.0,
                    c.image_size);
  std::pair<cv::Mat, cv::Mat> out;
  for (int side = 0; side < 2; ++side) {
    const CameraIntrinsics& camera = side == 0 ? c.left : c.right;
    cv::Mat map1, map2;
    cv::initUndistortRectifyMap(cv::Mat(camera.K), cv::Mat(camera.distortion), side == 0 ? R1 : R2, side == 0 ? P1 : P2,
                                c.image_size, CV_16SC2, map1, map2);
    cv::remap(side == 0 ? frame.left : frame.right, side == 0 ? out.first : out.second, map1, map2, cv::INTER_LINEAR,
              cv::BORDER_CONSTANT);
  }
  return out;
}

StereoFrame noiseFrame(cv::Size size, int type) {
  StereoFrame frame;
  frame.left = cv::Mat(size, type);
  frame.right = cv::Mat(size, type);
  cv::randu(frame.left, 0, 256);
  cv::randu(frame.right, 0, 256);
  return frame;
}

TEST(Rectifier, IdealRawRigHandsTheImagesOnAsCvRemapWouldReturnThem) {
  // No distortion, equal K, parallel cameras: the simulator's rig, given as a raw calibration.
  const test::RawCamera camera{cv::Matx33d(476.7, 0, 399.5, 0, 476.7, 299.5, 0, 0, 1), {0, 0, 0, 0}};
  const StereoCalibration c = test::rawRig(cv::Size(800, 600), camera, camera, cv::Vec3d(0, 0, 0), cv::Vec3d(-0.12, 0, 0));
  const Rectifier rectifier(c);
  ASSERT_FALSE(rectifier.isPassthrough());
  EXPECT_TRUE(rectifier.keepsImages());
  EXPECT_NEAR(rectifier.geometry().baseline_m, 0.12, 1e-12);
  for (const int type : {CV_8UC1, CV_8UC3}) {
    const StereoFrame frame = noiseFrame(c.image_size, type);
    const RectifiedPair pair = rectifier.rectify(frame);
    const auto [left, right] = remapWithOpenCv(c, frame);
    EXPECT_EQ(cv::norm(pair.left, left, cv::NORM_INF), 0.0) << "type " << type;
    EXPECT_EQ(cv::norm(pair.right, right, cv::NORM_INF), 0.0) << "type " << type;
    EXPECT_EQ(pair.left.data, frame.left.data) << "the left image is copied";
    EXPECT_EQ(pair.right.data, frame.right.data) << "the right image is copied";
  }
}

TEST(Rectifier, RigATenthOfAPixelFromIdealIsStillResampled) {
  // The right camera's principal point 0.2 px lower: each rectified view moves by 0.1 px (zero
  // disparity puts both principal points at the mean), so neither map is the identity.
  const test::RawCamera left{cv::Matx33d(476.7, 0, 399.5, 0, 476.7, 299.5, 0, 0, 1), {0, 0, 0, 0}};
  const test::RawCamera right{cv::Matx33d(476.7, 0, 399.5, 0, 476.7, 299.7, 0, 0, 1), {0, 0, 0, 0}};
  const StereoCalibration c = test::rawRig(cv::Size(800, 600), left, right, cv::Vec3d(0, 0, 0), cv::Vec3d(-0.12, 0, 0));
  const Rectifier rectifier(c);
  EXPECT_FALSE(rectifier.keepsImages());
  const StereoFrame frame = noiseFrame(c.image_size, CV_8UC3);
  const RectifiedPair pair = rectifier.rectify(frame);
  const auto [want_left, want_right] = remapWithOpenCv(c, frame);
  EXPECT_EQ(cv::norm(pair.left, want_left, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(pair.right, want_right, cv::NORM_INF), 0.0);
  EXPECT_GT(cv::norm(pair.left, frame.left, cv::NORM_INF), 0.0) << "the left image was not resampled";
  EXPECT_GT(cv::norm(pair.right, frame.right, cv::NORM_INF), 0.0) << "the right image was not resampled";
}

}  // namespace
}  // namespace cenote::pipeline
