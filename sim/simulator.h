// simulator.h: a calibrated stereo rig moving through a simulated underwater scene; renders each
// frame's pair, the left camera's exact depth and the poses (what `cenote sim` writes to disk).
//
// Rig: the body (IMU) frame is close to cam0's (T_body_cam0: 5 cm, about 3 degrees, so that extrinsics
// handling is exercised); cam1 = cam0 shifted by baseline_m along cam0's x axis, same orientation and
// intrinsics (fx = fy from hfov_deg, principal point at the image centre). With zero distortion the
// raw pair is already rectified: a point at (x, y) in the left image is at (x - f b / Z, y) in the right.
// Time: frame i is at t_s = i / rate_hz after the start; absolute timestamps are
// kSimStartTimeNs + round(t_s * 1e9) nanoseconds (an EuRoC-like clock).
// Units: metres, seconds, pixels. Frames: world z up; T_world_x maps x's points to the world.
// Threads: renderFrame() is const and may run for different frames on several threads at once; it
// also uses OpenMP inside (bands, rows). Output is bit-identical whatever the thread count.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "pipeline/calibration/stereo_calibration.h"
#include "sim/image_formation.h"
#include "sim/procedural_noise.h"
#include "sim/rasterizer.h"
#include "sim/sim_config.h"
#include "sim/sim_scene.h"

namespace cenote::sim {

inline constexpr int64_t kSimStartTimeNs = 1'700'000'000'000'000'000;

struct SimRig {
  PinholeCamera camera;            // both cameras
  std::vector<double> distortion;  // radial-tangential k1, k2, p1, p2 of both cameras
  double baseline_m = 0.0;
  Eigen::Isometry3d T_body_cam0 = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d T_body_cam1 = Eigen::Isometry3d::Identity();
};

struct SimFrame {
  int index = 0;
  int64_t t_ns = 0;        // absolute timestamp
  double t_s = 0.0;        // since the first frame
  cv::Mat left, right;     // CV_8UC3 BGR, as recorded (distorted when the rig has distortion)
  cv::Mat depth;           // CV_32F left camera, metres along the optical axis, +inf = no surface
                           // (with distortion also where the pixel's exact ray passes through no
                           // triangle seen by the 5 x 5 nearest pinhole pixels, which happens where
                           // triangles are smaller than a pixel: no ground truth, never a wrong one)
  cv::Mat left_triangles;  // CV_32S mesh triangle seen by each left pixel, -1 = none
  Eigen::Isometry3d T_world_body, T_world_cam0, T_world_cam1;
};

class Simulator {
 public:
  // Builds the scene and texture and fixes the exposure from the first frame.
  // @throws cenote::Error listing every invalid setting.
  explicit Simulator(const SimConfig& config);

  const SimConfig& config() const { return config_; }
  const SimScene& scene() const { return scene_; }
  const SimRig& rig() const { return rig_; }
  const SurfaceTexture& texture() const { return *texture_; }
  int numFrames() const { return config_.num_frames; }
  float gain() const { return gain_; }

  double frameTimeS(int index) const { return index / config_.rate_hz; }
  int64_t frameTimeNs(int index) const;
  // Poses at t_s seconds after the first frame (any t_s: trajectories extend before and after).
  Eigen::Isometry3d T_world_cam0(double t_s) const { return scene_.T_world_cam0(t_s); }
  Eigen::Isometry3d T_world_body(double t_s) const { return T_world_cam0(t_s) * rig_.T_body_cam0.inverse(); }

  // @throws cenote::Error when index is outside [0, numFrames()).
  SimFrame renderFrame(int index) const;

  // The raw rig in the project's calibration layout (p_right = R p_left + T).
  pipeline::StereoCalibration calibration() const;

 private:
  struct CameraImage {
    VisibilityBuffer visibility;
    cv::Mat radiance;
  };
  // Visibility and radiance of one camera, through the distortion model when there is one.
  CameraImage renderCamera(const Eigen::Isometry3d& T_world_cam, const Eigen::Isometry3d& T_world_light) const;
  // The recorded 8-bit image of one camera and its visibility (without distortion straight from
  // the shader, row by row, with no radiance image in memory).
  cv::Mat recordCamera(const Eigen::Isometry3d& T_world_cam, const Eigen::Isometry3d& T_world_light, float gain,
                       float noise_sigma, uint64_t noise_seed, VisibilityBuffer& visibility) const;

  SimConfig config_;
  SimScene scene_;
  SimRig rig_;
  std::unique_ptr<SurfaceTexture> texture_;
  float gain_ = 1.0f;
  // With distortion: the pinhole camera rendered, and for every output pixel its exact ray
  // (normalised x, y at z = 1) and its nearest pinhole pixel.
  PinholeCamera render_camera_;
  cv::Mat undistorted_rays_;  // CV_32FC2
  cv::Mat render_map_;        // CV_32FC2 pinhole pixel coordinates
};

}  // namespace cenote::sim
