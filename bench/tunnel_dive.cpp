#include "bench/tunnel_dive.h"

#include <cmath>

namespace cenote::bench {

TunnelDive makeTunnelDive(int frames, int moved, int width, int height, double drift_m, double drift_deg) {
  TunnelDive d;
  const double length = 0.4 / 15.0 * frames + 6.0;
  d.scene.boxes.push_back({Eigen::Vector3d(-2.0, -1.5, -1.25), Eigen::Vector3d(length, 1.5, 1.25)});
  for (int i = 0; i * 0.7 < length; ++i) {
    const double side = (i % 2 == 0) ? 1.0 : -1.0;
    d.scene.spheres.push_back({Eigen::Vector3d(0.7 * i, side * 1.5, -0.6 + 0.25 * (i % 5)), 0.25 + 0.05 * (i % 4)});
  }
  d.camera.width = width;
  d.camera.height = height;
  d.camera.fx = d.camera.fy = 0.75 * width;
  d.camera.cx = (width - 1) / 2.0;
  d.camera.cy = (height - 1) / 2.0;
  for (int i = 0; i < frames; ++i) {
    const double x = 0.4 / 15.0 * i;
    const Eigen::Vector3d position(x, 0.3 * std::sin(0.05 * i), 0.1 * std::sin(0.03 * i));
    const double yaw = 0.35 * std::sin(0.02 * i);
    const Eigen::Isometry3d T = mapping::test::lookAt(position,
                                                      position + Eigen::Vector3d(std::cos(yaw), std::sin(yaw), -0.05));
    d.truth.push_back(T);
    const int first_moved = frames - moved;
    const double u = i < first_moved ? 0.0 : (i - first_moved + 1.0) / moved;
    Eigen::Isometry3d D = Eigen::Isometry3d::Identity();
    D.linear() = Eigen::AngleAxisd(u * drift_deg * M_PI / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    D.translation() = Eigen::Vector3d(u * drift_m, u * drift_m, 0.0);
    d.drifted.push_back(D * T);
  }
  return d;
}

PointBatch tunnelFrame(const TunnelDive& d, int i, const Eigen::Isometry3d& T) {
  PointBatch seen = mapping::test::renderBatch(d.scene, d.camera, d.truth[i], 10.0, 0.01, 1000 + i);
  seen.t_s = i / 15.0;
  const Eigen::Isometry3d T_delta = T * d.truth[i].inverse();
  for (Eigen::Vector3f& p : seen.points) p = (T_delta * p.cast<double>()).cast<float>();
  seen.origin = T.translation();
  return seen;
}

std::vector<mapping::CorrectedPose> trueTunnelPoses(const TunnelDive& d) {
  std::vector<mapping::CorrectedPose> poses;
  for (size_t i = 0; i < d.truth.size(); ++i) poses.push_back({i / 15.0, d.truth[i]});
  return poses;
}

}  // namespace cenote::bench
