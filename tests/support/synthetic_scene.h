// synthetic_scene.h: scenes of known geometry for fusion tests and benchmarks, a ray-caster that
// renders exact depth and colour from known poses, and a stereo noise model.
// Units: metres, pixels. Frames: world; cameras look along their +z (T_world_cam). The scenes put
// the surfaces at world z of about 2-4 m in front of cameras near z = 0 looking along world +z
// (a down-looking survey: world z is depth below the vehicle).
// Threads: pure functions; renderScene() uses OpenMP over rows.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

#include "pipeline/frame/frames.h"

namespace cenote::test {

struct Plane {
  Eigen::Vector3d point, normal;
};
struct Box {
  Eigen::Vector3d min, max;
};
// Height field z = base_z + amplitude * sin(kx x) * cos(ky y) (a "reef").
struct Reef {
  double base_z = 3.0, amplitude = 0.3, kx = 2.0, ky = 1.5;
};

struct Scene {
  std::vector<Plane> planes;
  std::vector<Box> boxes;
  std::vector<Reef> reefs;

  // Distance s >= min_s along the unit ray o + s d to the nearest surface; +inf when none.
  double intersect(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double min_s = 1e-6) const;
  // Procedural colour (BGR) of a world point: smooth stripes in x, y, z.
  cv::Vec3b colorAt(const Eigen::Vector3d& p_world) const;
};

Scene planeScene();  // a slanted plane, 2.5-3.5 m
Scene boxScene();    // two boxes standing in front of a back plane at 4 m (occlusion edges)
Scene reefScene();   // a sinusoidal reef around 3 m

// Camera of the tests: width x height, focal length, principal point at the centre.
struct TestCamera {
  int width = 320, height = 240;
  double focal_px = 260.0;
  Eigen::Matrix3d K() const;
};

// Poses along a survey line: camera i at x = (i - (n-1)/2) * step_m, small yaw / pitch changes.
std::vector<Eigen::Isometry3d> surveyPoses(int n, double step_m);

// Exact depth (CV_32F metres along the optical axis, +inf where no surface) and colour (CV_8UC3).
pipeline::DepthFrame renderScene(const Scene& scene, const TestCamera& camera, const Eigen::Isometry3d& T_world_cam,
                                 double t_s);

// Stereo-like corruption of an exact depth map.
struct StereoNoise {
  double focal_baseline_px_m = 39.0;                  // f * b: disparity = f b / Z
  double sigma_disparity_px = 0.25;                   // Gaussian disparity noise -> sigma_Z = Z^2 sigma_d / (f b)
  double outlier_fraction = 0.07;                     // gross outliers: disparity off by 3-20 px either way
  double hole_fraction = 0.05;                        // pixels lost in blobs (textureless patches)
  double min_confidence = 0.6, max_confidence = 1.4;  // confidence uniform in this range, unrelated to error
};

// StereoNoise of a rig of `camera` with baseline `baseline_m` (f b = camera.focal_px * baseline_m).
StereoNoise stereoNoiseFor(const TestCamera& camera, double baseline_m);

struct NoisyDepth {
  cv::Mat depth;       // CV_32F, +inf in holes
  cv::Mat confidence;  // CV_32F, 0 in holes
  cv::Mat outliers;    // CV_8U, 255 where a gross outlier was injected
};

NoisyDepth addStereoNoise(const cv::Mat& true_depth, const StereoNoise& noise, uint32_t seed);

// A depth error is gross when it exceeds `disparity_px` in disparity: |dZ| > disparity_px Z^2 / (f b).
bool isGrossError(double estimate_m, double truth_m, double focal_baseline_px_m, double disparity_px = 1.0);

}  // namespace cenote::test
