#include "sim/simulator.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <string>

#include "common/error.h"

namespace cenote::sim {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kExposurePercentile = 95.0;
constexpr float kExposureTarget = 0.8f;  // linear value of that percentile in the first left image
constexpr double kMaxCanvasScale = 3.0;  // the pinhole canvas behind a distorted image, at most

// Normalised undistorted coordinates of a distorted normalised point (radial k1, k2) by
// fixed-point iteration; false when it does not converge (distortion too strong at that radius).
bool undistortRadial(double xd, double yd, double k1, double k2, double& xu, double& yu) {
  xu = xd;
  yu = yd;
  for (int i = 0; i < 50; ++i) {
    const double r2 = xu * xu + yu * yu;
    const double f = 1.0 + k1 * r2 + k2 * r2 * r2;
    if (!(f > 0.05)) return false;
    xu = xd / f;
    yu = yd / f;
  }
  const double r2 = xu * xu + yu * yu;
  const double f = 1.0 + k1 * r2 + k2 * r2 * r2;
  return std::abs(xu * f - xd) < 1e-9 && std::abs(yu * f - yd) < 1e-9;
}

// Depth (z of the hit, the ray has z = 1) where the ray from the camera centre passes through mesh
// triangle t (Moller-Trumbore, camera frame); +inf when it misses.
double rayTriangleDepth(const SceneMesh& mesh, int32_t t, const Eigen::Isometry3d& T_cam_world,
                        const Eigen::Vector3d& ray) {
  const auto& tri = mesh.triangles[t];
  const Eigen::Vector3d v0 = T_cam_world * mesh.vertices[tri[0]].cast<double>();
  const Eigen::Vector3d e1 = T_cam_world * mesh.vertices[tri[1]].cast<double>() - v0;
  const Eigen::Vector3d e2 = T_cam_world * mesh.vertices[tri[2]].cast<double>() - v0;
  const Eigen::Vector3d p = ray.cross(e2);
  const double det = e1.dot(p);
  if (std::abs(det) < 1e-18) return std::numeric_limits<double>::infinity();
  const Eigen::Vector3d s = -v0;
  const double u = s.dot(p) / det;
  const Eigen::Vector3d q = s.cross(e1);
  const double v = ray.dot(q) / det;
  constexpr double kSlack = 1e-9;
  if (u < -kSlack || v < -kSlack || u + v > 1.0 + kSlack) return std::numeric_limits<double>::infinity();
  const double z = e2.dot(q) / det;
  return z > 0 ? z : std::numeric_limits<double>::infinity();
}

}  // namespace

Simulator::Simulator(const SimConfig& config) : config_(config) {
  throwIfInvalid(config.validate(), "sim");
  scene_ = buildScene(config);
  texture_ = std::make_unique<SurfaceTexture>(hash64(static_cast<uint64_t>(config.seed), 0x7E47));

  PinholeCamera& cam = rig_.camera;
  cam.width = config.width_px;
  cam.height = config.height_px;
  cam.fx = cam.fy = 0.5 * config.width_px / std::tan(0.5 * config.hfov_deg * kPi / 180.0);
  cam.cx = 0.5 * (config.width_px - 1);
  cam.cy = 0.5 * (config.height_px - 1);
  rig_.distortion = {config.k1, config.k2, 0.0, 0.0};
  rig_.baseline_m = config.baseline_m;
  rig_.T_body_cam0.linear() =
      Eigen::AngleAxisd(3.0 * kPi / 180.0, Eigen::Vector3d(0.3, -0.5, 0.8).normalized()).toRotationMatrix();
  rig_.T_body_cam0.translation() = Eigen::Vector3d(0.04, -0.02, 0.025);
  rig_.T_body_cam1 = rig_.T_body_cam0 * Eigen::Translation3d(config.baseline_m, 0.0, 0.0);

  render_camera_ = cam;
  if (config.k1 != 0.0 || config.k2 != 0.0) {
    undistorted_rays_.create(cam.height, cam.width, CV_32FC2);
    render_map_.create(cam.height, cam.width, CV_32FC2);
    double min_x = 1e300, max_x = -1e300, min_y = 1e300, max_y = -1e300;
    for (int y = 0; y < cam.height; ++y) {
      for (int x = 0; x < cam.width; ++x) {
        double xu, yu;
        if (!undistortRadial((x - cam.cx) / cam.fx, (y - cam.cy) / cam.fy, config.k1, config.k2, xu, yu)) {
          throw Error("sim: distortion k1 = " + std::to_string(config.k1) + ", k2 = " + std::to_string(config.k2) +
                      " cannot be inverted at pixel (" + std::to_string(x) + ", " + std::to_string(y) +
                      "); use smaller coefficients or a narrower hfov_deg");
        }
        undistorted_rays_.at<cv::Vec2f>(y, x) = cv::Vec2f(static_cast<float>(xu), static_cast<float>(yu));
        min_x = std::min(min_x, xu * cam.fx);
        max_x = std::max(max_x, xu * cam.fx);
        min_y = std::min(min_y, yu * cam.fy);
        max_y = std::max(max_y, yu * cam.fy);
      }
    }
    render_camera_.cx = std::ceil(-min_x) + 2.0;
    render_camera_.cy = std::ceil(-min_y) + 2.0;
    render_camera_.width = static_cast<int>(std::ceil(render_camera_.cx + max_x)) + 3;
    render_camera_.height = static_cast<int>(std::ceil(render_camera_.cy + max_y)) + 3;
    if (render_camera_.width > kMaxCanvasScale * cam.width || render_camera_.height > kMaxCanvasScale * cam.height) {
      throw Error("sim: distortion k1 = " + std::to_string(config.k1) + ", k2 = " + std::to_string(config.k2) +
                  " needs a pinhole canvas of " + std::to_string(render_camera_.width) + "x" +
                  std::to_string(render_camera_.height) + " pixels; use smaller coefficients or a narrower hfov_deg");
    }
    for (int y = 0; y < cam.height; ++y) {
      for (int x = 0; x < cam.width; ++x) {
        const cv::Vec2f r = undistorted_rays_.at<cv::Vec2f>(y, x);
        render_map_.at<cv::Vec2f>(y, x) = cv::Vec2f(static_cast<float>(r[0] * cam.fx + render_camera_.cx),
                                                    static_cast<float>(r[1] * cam.fy + render_camera_.cy));
      }
    }
  }
  // Exposure from the first left image, then fixed for the whole sequence (a locked camera).
  const Eigen::Isometry3d T0 = T_world_cam0(0.0);
  const CameraImage first = renderCamera(T0, T0);
  gain_ = autoExposureGain(first.radiance, first.visibility, kExposurePercentile, kExposureTarget);
}

int64_t Simulator::frameTimeNs(int index) const {
  return kSimStartTimeNs + static_cast<int64_t>(std::llround(frameTimeS(index) * 1e9));
}

Simulator::CameraImage Simulator::renderCamera(const Eigen::Isometry3d& T_world_cam,
                                               const Eigen::Isometry3d& T_world_light) const {
  CameraImage image;
  image.visibility = rasterize(scene_.mesh, render_camera_, T_world_cam);
  image.radiance = renderRadiance(scene_, *texture_, render_camera_, T_world_cam, image.visibility, T_world_light);
  if (undistorted_rays_.empty()) return image;

  // Through the distortion model: radiance resampled bilinearly from the pinhole image; depth exact
  // along each pixel's own ray.
  const PinholeCamera& cam = rig_.camera;
  CameraImage out;
  cv::remap(image.radiance, out.radiance, render_map_, cv::noArray(), cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  out.visibility.triangle.create(cam.height, cam.width, CV_32S);
  out.visibility.depth.create(cam.height, cam.width, CV_32F);
  const Eigen::Isometry3d T_cam_world = T_world_cam.inverse();
  const float inf = std::numeric_limits<float>::infinity();
#pragma omp parallel for schedule(static)
  for (int y = 0; y < cam.height; ++y) {
    for (int x = 0; x < cam.width; ++x) {
      const cv::Vec2f m = render_map_.at<cv::Vec2f>(y, x);
      const int px = std::clamp(static_cast<int>(std::lround(m[0])), 0, render_camera_.width - 1);
      const int py = std::clamp(static_cast<int>(std::lround(m[1])), 0, render_camera_.height - 1);
      // The ray of this pixel against the triangles of the nearest pinhole pixels (3 x 3, then 5 x 5):
      // the nearest one it passes through. When it passes through none of them (a sliver seen edge-on
      // between pinhole pixels) the pixel gets no ground truth rather than a wrong one.
      const cv::Vec2f r = undistorted_rays_.at<cv::Vec2f>(y, x);
      const Eigen::Vector3d ray(r[0], r[1], 1.0);
      int32_t t = -1;
      float z = inf;
      for (int radius = 1; radius <= 2 && t < 0; ++radius) {
        for (int dy = -radius; dy <= radius; ++dy) {
          for (int dx = -radius; dx <= radius; ++dx) {
            const int qx = std::clamp(px + dx, 0, render_camera_.width - 1);
            const int qy = std::clamp(py + dy, 0, render_camera_.height - 1);
            const int32_t candidate = image.visibility.triangle.at<int32_t>(qy, qx);
            if (candidate < 0) continue;
            const double hit = rayTriangleDepth(scene_.mesh, candidate, T_cam_world, ray);
            if (hit < z) {
              z = static_cast<float>(hit);
              t = candidate;
            }
          }
        }
      }
      out.visibility.triangle.at<int32_t>(y, x) = std::isfinite(z) ? t : -1;
      out.visibility.depth.at<float>(y, x) = z;
    }
  }
  return out;
}

SimFrame Simulator::renderFrame(int index) const {
  if (index < 0 || index >= numFrames()) {
    throw Error("sim: frame " + std::to_string(index) + " is outside [0, " + std::to_string(numFrames()) + ")");
  }
  SimFrame frame;
  frame.index = index;
  frame.t_s = frameTimeS(index);
  frame.t_ns = frameTimeNs(index);
  frame.T_world_cam0 = T_world_cam0(frame.t_s);
  frame.T_world_body = frame.T_world_cam0 * rig_.T_body_cam0.inverse();
  frame.T_world_cam1 = frame.T_world_body * rig_.T_body_cam1;
  const auto seed = static_cast<uint64_t>(config_.seed);
  const auto sigma = static_cast<float>(config_.noise_sigma);
  VisibilityBuffer left;
  frame.left = recordCamera(frame.T_world_cam0, frame.T_world_cam0, gain_, sigma, hash64(seed, 0x5E45, index, 0), left);
  frame.depth = left.depth;
  frame.left_triangles = left.triangle;
  VisibilityBuffer right;
  frame.right = recordCamera(frame.T_world_cam1, frame.T_world_cam0, gain_ * static_cast<float>(config_.exposure_ratio),
                             sigma, hash64(seed, 0x5E45, index, 1), right);
  return frame;
}

cv::Mat Simulator::recordCamera(const Eigen::Isometry3d& T_world_cam, const Eigen::Isometry3d& T_world_light, float gain,
                                float noise_sigma, uint64_t noise_seed, VisibilityBuffer& visibility) const {
  if (undistorted_rays_.empty()) {
    visibility = rasterize(scene_.mesh, render_camera_, T_world_cam);
    return renderImage(scene_, *texture_, render_camera_, T_world_cam, visibility, T_world_light, gain, noise_sigma,
                       noise_seed);
  }
  CameraImage image = renderCamera(T_world_cam, T_world_light);
  visibility = std::move(image.visibility);
  return exposeImage(image.radiance, gain, noise_sigma, noise_seed);
}

pipeline::StereoCalibration Simulator::calibration() const {
  pipeline::StereoCalibration c;
  const PinholeCamera& cam = rig_.camera;
  c.image_size = cv::Size(cam.width, cam.height);
  c.left.K = cv::Matx33d(cam.fx, 0, cam.cx, 0, cam.fy, cam.cy, 0, 0, 1);
  c.left.distortion = rig_.distortion;
  c.right = c.left;
  const Eigen::Isometry3d T_cam1_cam0 = rig_.T_body_cam1.inverse() * rig_.T_body_cam0;
  for (int r = 0; r < 3; ++r) {
    for (int k = 0; k < 3; ++k) c.R(r, k) = T_cam1_cam0.linear()(r, k);
    c.T[r] = T_cam1_cam0.translation()[r];
  }
  return c;
}

}  // namespace cenote::sim
