#include "tests/support/synthetic_scene.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <random>

namespace cenote::test {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

double intersectPlane(const Plane& plane, const Eigen::Vector3d& o, const Eigen::Vector3d& d, double min_s) {
  const double denom = plane.normal.dot(d);
  if (std::abs(denom) < 1e-12) return kInf;
  const double s = plane.normal.dot(plane.point - o) / denom;
  return s >= min_s ? s : kInf;
}

double intersectBox(const Box& box, const Eigen::Vector3d& o, const Eigen::Vector3d& d, double min_s) {
  double near = -kInf, far = kInf;
  for (int a = 0; a < 3; ++a) {
    if (std::abs(d[a]) < 1e-12) {
      if (o[a] < box.min[a] || o[a] > box.max[a]) return kInf;
      continue;
    }
    double s0 = (box.min[a] - o[a]) / d[a], s1 = (box.max[a] - o[a]) / d[a];
    if (s0 > s1) std::swap(s0, s1);
    near = std::max(near, s0);
    far = std::min(far, s1);
  }
  if (near > far) return kInf;
  if (near >= min_s) return near;
  return far >= min_s ? far : kInf;
}

double reefHeight(const Reef& reef, double x, double y) {
  return reef.base_z + reef.amplitude * std::sin(reef.kx * x) * std::cos(reef.ky * y);
}

// The reef is below (larger z than) the ray's start; march through its slab, then bisect.
double intersectReef(const Reef& reef, const Eigen::Vector3d& o, const Eigen::Vector3d& d, double min_s) {
  if (d.z() <= 1e-9) return kInf;
  auto g = [&](double s) {
    const Eigen::Vector3d p = o + s * d;
    return p.z() - reefHeight(reef, p.x(), p.y());
  };
  const double top = reef.base_z - std::abs(reef.amplitude) - 1e-3;
  const double bottom = reef.base_z + std::abs(reef.amplitude) + 1e-3;
  double s0 = std::max(min_s, (top - o.z()) / d.z());
  const double s_end = (bottom - o.z()) / d.z();
  if (s_end < s0) return kInf;
  constexpr int kSteps = 96;
  const double step = (s_end - s0) / kSteps;
  double g0 = g(s0);
  if (g0 >= 0.0) return s0;
  for (int i = 1; i <= kSteps; ++i) {
    const double s1 = s0 + step;
    const double g1 = g(s1);
    if (g1 >= 0.0) {
      double lo = s0, hi = s1;
      for (int it = 0; it < 50; ++it) {
        const double mid = 0.5 * (lo + hi);
        (g(mid) >= 0.0 ? hi : lo) = mid;
      }
      return 0.5 * (lo + hi);
    }
    s0 = s1;
    g0 = g1;
  }
  return kInf;
}

}  // namespace

double Scene::intersect(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double min_s) const {
  double best = kInf;
  for (const Plane& p : planes) best = std::min(best, intersectPlane(p, o, d, min_s));
  for (const Box& b : boxes) best = std::min(best, intersectBox(b, o, d, min_s));
  for (const Reef& r : reefs) best = std::min(best, intersectReef(r, o, d, min_s));
  return best;
}

cv::Vec3b Scene::colorAt(const Eigen::Vector3d& p) const {
  auto channel = [](double v) { return static_cast<uint8_t>(std::clamp(128.0 + 100.0 * std::sin(v), 0.0, 255.0)); };
  return {channel(7.0 * p.x()), channel(5.0 * p.y() + 1.0), channel(3.0 * p.z() + 2.0)};
}

Scene planeScene() {
  Scene s;
  s.planes.push_back({Eigen::Vector3d(0.0, 0.0, 3.0), Eigen::Vector3d(0.25, 0.15, -1.0).normalized()});
  return s;
}

Scene boxScene() {
  Scene s;
  s.planes.push_back({Eigen::Vector3d(0.0, 0.0, 4.0), Eigen::Vector3d(0.05, 0.1, -1.0).normalized()});
  s.boxes.push_back({Eigen::Vector3d(-0.9, -0.5, 2.4), Eigen::Vector3d(-0.2, 0.3, 3.0)});
  s.boxes.push_back({Eigen::Vector3d(0.3, -0.7, 3.0), Eigen::Vector3d(0.9, 0.2, 3.5)});
  return s;
}

Scene reefScene() {
  Scene s;
  s.reefs.push_back(Reef{});
  return s;
}

Eigen::Matrix3d TestCamera::K() const {
  Eigen::Matrix3d k;
  k << focal_px, 0.0, 0.5 * (width - 1), 0.0, focal_px, 0.5 * (height - 1), 0.0, 0.0, 1.0;
  return k;
}

std::vector<Eigen::Isometry3d> surveyPoses(int n, double step_m) {
  std::vector<Eigen::Isometry3d> poses;
  for (int i = 0; i < n; ++i) {
    const double k = i - 0.5 * (n - 1);
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = (Eigen::AngleAxisd(0.012 * k, Eigen::Vector3d::UnitY()) *
                  Eigen::AngleAxisd(0.008 * std::sin(1.3 * k), Eigen::Vector3d::UnitX()) *
                  Eigen::AngleAxisd(0.01 * k, Eigen::Vector3d::UnitZ()))
                     .toRotationMatrix();
    T.translation() = Eigen::Vector3d(k * step_m, 0.02 * std::sin(0.9 * k), 0.03 * std::cos(0.7 * k));
    poses.push_back(T);
  }
  return poses;
}

pipeline::DepthFrame renderScene(const Scene& scene, const TestCamera& camera, const Eigen::Isometry3d& T_world_cam,
                                 double t_s) {
  pipeline::DepthFrame frame;
  frame.t_s = t_s;
  frame.K = camera.K();
  frame.T_world_cam = T_world_cam;
  frame.depth.create(camera.height, camera.width, CV_32F);
  frame.confidence = cv::Mat(camera.height, camera.width, CV_32F, cv::Scalar(1.0f));
  frame.color = cv::Mat(camera.height, camera.width, CV_8UC3, cv::Scalar::all(0));
  const Eigen::Matrix3d K_inv = frame.K.inverse();
  const Eigen::Vector3d origin = T_world_cam.translation();
#pragma omp parallel for schedule(dynamic, 4)
  for (int y = 0; y < camera.height; ++y) {
    for (int x = 0; x < camera.width; ++x) {
      const Eigen::Vector3d ray_cam = K_inv * Eigen::Vector3d(x, y, 1.0);  // z = 1
      const Eigen::Vector3d dir = (T_world_cam.linear() * ray_cam).normalized();
      const double s = scene.intersect(origin, dir);
      if (!std::isfinite(s)) {
        frame.depth.at<float>(y, x) = std::numeric_limits<float>::infinity();
        frame.confidence.at<float>(y, x) = 0.0f;
        continue;
      }
      const Eigen::Vector3d p_world = origin + s * dir;
      frame.depth.at<float>(y, x) = static_cast<float>(s / ray_cam.norm());
      frame.color.at<cv::Vec3b>(y, x) = scene.colorAt(p_world);
    }
  }
  return frame;
}

NoisyDepth addStereoNoise(const cv::Mat& true_depth, const StereoNoise& noise, uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> gauss(0.0, noise.sigma_disparity_px);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  NoisyDepth out;
  out.depth = true_depth.clone();
  out.confidence.create(true_depth.size(), CV_32F);
  out.outliers = cv::Mat(true_depth.size(), CV_8U, cv::Scalar(0));
  cv::Mat holes(true_depth.size(), CV_8U, cv::Scalar(0));
  // Holes: discs of radius 2-8 px until the fraction is reached.
  const double target = noise.hole_fraction * true_depth.total();
  while (cv::countNonZero(holes) < target) {
    const int cx = static_cast<int>(unit(rng) * true_depth.cols), cy = static_cast<int>(unit(rng) * true_depth.rows);
    cv::circle(holes, {cx, cy}, 2 + static_cast<int>(unit(rng) * 7), cv::Scalar(255), cv::FILLED);
  }
  const double fb = noise.focal_baseline_px_m;
  for (int y = 0; y < true_depth.rows; ++y) {
    for (int x = 0; x < true_depth.cols; ++x) {
      const float z = true_depth.at<float>(y, x);
      float& out_z = out.depth.at<float>(y, x);
      float& out_c = out.confidence.at<float>(y, x);
      const double draw_outlier = unit(rng), draw_noise = gauss(rng), draw_conf = unit(rng);
      const double draw_size = unit(rng), draw_sign = unit(rng);
      if (!std::isfinite(z) || holes.at<uint8_t>(y, x)) {
        out_z = std::numeric_limits<float>::infinity();
        out_c = 0.0f;
        continue;
      }
      double disparity = fb / z;
      if (draw_outlier < noise.outlier_fraction) {
        const double jump = 3.0 + 17.0 * draw_size;
        disparity += draw_sign < 0.5 ? -jump : jump;
        disparity = std::max(disparity, 1.0);
        out.outliers.at<uint8_t>(y, x) = 255;
      } else {
        disparity += draw_noise;
      }
      out_z = static_cast<float>(fb / disparity);
      out_c = static_cast<float>(noise.min_confidence + (noise.max_confidence - noise.min_confidence) * draw_conf);
    }
  }
  return out;
}

bool isGrossError(double estimate_m, double truth_m, double focal_baseline_px_m, double disparity_px) {
  return std::abs(estimate_m - truth_m) > disparity_px * truth_m * truth_m / focal_baseline_px_m;
}

StereoNoise stereoNoiseFor(const TestCamera& camera, double baseline_m) {
  StereoNoise noise;
  noise.focal_baseline_px_m = camera.focal_px * baseline_m;
  return noise;
}

}  // namespace cenote::test
