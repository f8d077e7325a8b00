#include "tests/mapping/support/drifted_frames.h"

#include <cmath>

namespace cenote::mapping::test {

PointBatch DriftedFrame::batchAt(const Eigen::Isometry3d& T) const {
  PointBatch batch;
  batch.t_s = t_s;
  batch.origin = T.translation();
  batch.points.reserve(points_cam.size());
  for (const Eigen::Vector3f& p : points_cam) batch.points.push_back((T * p.cast<double>()).cast<float>());
  batch.colors = colors;
  return batch;
}

Scene driftedRoom() {
  Scene scene;
  scene.boxes.push_back({Eigen::Vector3d(-3, -2, -1.5), Eigen::Vector3d(3, 2, 1.5)});
  scene.spheres.push_back({Eigen::Vector3d(1.5, 0.8, -0.7), 0.5});
  scene.spheres.push_back({Eigen::Vector3d(-1.2, -0.9, 0.2), 0.4});
  return scene;
}

std::vector<DriftedFrame> driftedRoomSweep(int frames, const PinholeCamera& camera, double drift_m, double drift_deg,
                                           double quantum_m) {
  const Scene scene = driftedRoom();
  std::vector<DriftedFrame> out(frames);
  for (int i = 0; i < frames; ++i) {
    const double u = frames > 1 ? static_cast<double>(i) / (frames - 1) : 0.0;
    const double angle = 2.0 * M_PI * u;
    const Eigen::Vector3d position(1.2 * std::cos(angle), 0.8 * std::sin(angle), 0.1 * std::sin(3 * angle));
    const Eigen::Vector3d target = position + Eigen::Vector3d(-std::sin(angle + 0.6), std::cos(angle + 0.6), -0.15);
    DriftedFrame& f = out[i];
    f.t_s = 0.1 * i;
    f.T_true = lookAt(position, target);
    Eigen::Isometry3d D = Eigen::Isometry3d::Identity();
    D.linear() = Eigen::AngleAxisd(u * drift_deg * M_PI / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    D.translation() = Eigen::Vector3d(u * drift_m, u * drift_m, 0.0);
    f.T_drifted = D * f.T_true;
    const PointBatch seen = renderBatch(scene, camera, f.T_true, 8.0);
    const Eigen::Isometry3d T_cam_world = f.T_true.inverse();
    for (const Eigen::Vector3f& p : seen.points) {
      const Eigen::Vector3d p_cam = T_cam_world * p.cast<double>();
      f.points_cam.push_back(((p_cam / quantum_m).array().round() * quantum_m).matrix().cast<float>());
    }
    f.colors = seen.colors;
  }
  return out;
}

}  // namespace cenote::mapping::test
