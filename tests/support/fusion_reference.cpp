#include "tests/support/fusion_reference.h"

#include <chrono>
#include <cmath>
#include <limits>

namespace cenote::test {
namespace {

using pipeline::DepthFrame;
using pipeline::FusionConfig;

constexpr double kInf = std::numeric_limits<double>::infinity();

struct Candidate {
  double depth_m, confidence;
  int view;
};

bool isValid(const FusionConfig& config, double depth_m, double confidence) {
  return std::isfinite(depth_m) && depth_m > 0.0 && depth_m <= config.max_depth_m && confidence > 0.0 &&
         confidence >= config.min_input_confidence;
}

double epsAt(const FusionConfig& config, double depth_m) {
  return config.support_radius == pipeline::SupportRadius::kRelative ? config.eps * depth_m : config.eps;
}

// Nearest pixel of a point in camera coordinates; false when behind the camera or outside.
bool project(const Eigen::Matrix3d& K, const Eigen::Vector3d& p_cam, cv::Size size, int& x, int& y) {
  if (!(p_cam.z() > 0.0)) return false;
  const Eigen::Vector3d h = K * p_cam;
  const double u = h.x() / h.z(), v = h.y() / h.z();
  x = static_cast<int>(std::floor(u + 0.5));
  y = static_cast<int>(std::floor(v + 0.5));
  return u >= -0.5 && v >= -0.5 && x >= 0 && y >= 0 && x < size.width && y < size.height;
}

double msSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

DepthFrame fuseViewsReference(const std::vector<const DepthFrame*>& views, const FusionConfig& config,
                              ReferenceFusionTimings* timings) {
  const int n = static_cast<int>(views.size());
  const int r = (n - 1) / 2;
  const DepthFrame& ref = *views[r];
  const cv::Size size = ref.depth.size();

  // Rendering: z-buffer of every other view in the reference.
  auto start = std::chrono::steady_clock::now();
  std::vector<cv::Mat> rendered_depth(n), rendered_conf(n);
  for (int k = 0; k < n; ++k) {
    if (k == r) continue;
    rendered_depth[k] = cv::Mat(size, CV_64F, cv::Scalar(kInf));
    rendered_conf[k] = cv::Mat(size, CV_64F, cv::Scalar(0.0));
    const DepthFrame& view = *views[k];
    const Eigen::Isometry3d T_ref_k = ref.T_world_cam.inverse() * view.T_world_cam;
    const Eigen::Matrix3d K_inv = view.K.inverse();
    for (int y = 0; y < size.height; ++y) {
      for (int x = 0; x < size.width; ++x) {
        const double z = view.depth.at<float>(y, x), c = view.confidence.at<float>(y, x);
        if (!isValid(config, z, c)) continue;
        const Eigen::Vector3d p_ref = T_ref_k * (z * (K_inv * Eigen::Vector3d(x, y, 1.0)));
        int u, v;
        if (!project(ref.K, p_ref, size, u, v)) continue;
        if (p_ref.z() < rendered_depth[k].at<double>(v, u)) {
          rendered_depth[k].at<double>(v, u) = p_ref.z();
          rendered_conf[k].at<double>(v, u) = c;
        }
      }
    }
  }
  if (timings) timings->render_ms = msSince(start);

  start = std::chrono::steady_clock::now();
  std::vector<Eigen::Isometry3d> T_l_ref(n);
  for (int l = 0; l < n; ++l) T_l_ref[l] = views[l]->T_world_cam.inverse() * ref.T_world_cam;
  const Eigen::Matrix3d K_ref_inv = ref.K.inverse();
  DepthFrame fused;
  fused.t_s = ref.t_s;
  fused.K = ref.K;
  fused.T_world_cam = ref.T_world_cam;
  fused.color = ref.color;
  fused.depth = cv::Mat(size, CV_32F, cv::Scalar(std::numeric_limits<float>::infinity()));
  fused.confidence = cv::Mat(size, CV_32F, cv::Scalar(0.0f));
  for (int y = 0; y < size.height; ++y) {
    for (int x = 0; x < size.width; ++x) {
      std::vector<Candidate> candidates;
      for (int v = 0; v < n; ++v) {
        if (v == r) {
          const double z = ref.depth.at<float>(y, x), c = ref.confidence.at<float>(y, x);
          if (isValid(config, z, c)) candidates.push_back({z, c, v});
        } else if (std::isfinite(rendered_depth[v].at<double>(y, x))) {
          candidates.push_back({rendered_depth[v].at<double>(y, x), rendered_conf[v].at<double>(y, x), v});
        }
      }
      const Eigen::Vector3d ray = K_ref_inv * Eigen::Vector3d(x, y, 1.0);
      double best_conf = -kInf, best_depth = kInf;
      for (const Candidate& j : candidates) {
        const double e = epsAt(config, j.depth_m);
        double support = 0.0, weighted = 0.0, conflict = 0.0;
        for (const Candidate& i : candidates) {
          if (std::abs(i.depth_m - j.depth_m) < e) {
            support += i.confidence;
            weighted += i.confidence * i.depth_m;
          } else if (i.depth_m < j.depth_m - e) {
            conflict += i.confidence;  // occlusion
          }
        }
        for (int l = 0; l < n; ++l) {
          if (l == j.view) continue;
          const Eigen::Vector3d p_l = T_l_ref[l] * (j.depth_m * ray);
          int u, v;
          if (!project(views[l]->K, p_l, size, u, v)) continue;
          const double zl = views[l]->depth.at<float>(v, u), cl = views[l]->confidence.at<float>(v, u);
          if (isValid(config, zl, cl) && p_l.z() < zl - epsAt(config, p_l.z())) conflict += cl;  // free space
        }
        const double fused_conf = support - conflict;
        if (fused_conf > best_conf) {
          best_conf = fused_conf;
          best_depth = weighted / support;
        }
      }
      if (best_conf >= config.min_fused_confidence) {
        fused.depth.at<float>(y, x) = static_cast<float>(best_depth);
        fused.confidence.at<float>(y, x) = static_cast<float>(best_conf);
      }
    }
  }
  if (timings) timings->fuse_ms = msSince(start);
  return fused;
}

}  // namespace cenote::test
