// make_scan_graph: writes an OctoMap ScanGraph (.graph) of a survey over an analytic sea floor
// (points in the sensor frame, one pose each), for the `cenote map integrate` vs graph2tree test.
//   make_scan_graph OUT.graph [NUM_SCANS]
#include <octomap/ScanGraph.h>

#include <cstdio>
#include <cstdlib>

#include "tests/mapping/support/analytic_scene.h"

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: make_scan_graph OUT.graph [NUM_SCANS]\n");
    return 1;
  }
  const int num_scans = argc > 2 ? std::atoi(argv[2]) : 4;
  using namespace cenote::mapping::test;
  Scene scene;
  scene.planes.push_back({Eigen::Vector3d(0, 0, -2.0), Eigen::Vector3d(0.05, 0.02, 1.0).normalized()});
  scene.spheres.push_back({Eigen::Vector3d(4.0, 0.5, -2.0), 0.7});
  scene.spheres.push_back({Eigen::Vector3d(5.0, -1.0, -1.8), 0.5});
  cenote::PinholeCamera camera;
  camera.width = 320;
  camera.height = 240;
  camera.fx = camera.fy = 240.0;
  camera.cx = 159.5;
  camera.cy = 119.5;
  octomap::ScanGraph graph;
  for (int i = 0; i < num_scans; ++i) {
    const Eigen::Vector3d position(0.4 * i + 0.013, 0.1 * i, 0.02 * i);
    const Eigen::Isometry3d T_world_cam = lookAt(position, position + Eigen::Vector3d(3.0, 0.2, -1.5));
    const cenote::PointBatch batch = renderBatch(scene, camera, T_world_cam, 12.0, 0.01, 40 + i);
    auto* scan = new octomap::Pointcloud();
    const Eigen::Isometry3d T_cam_world = T_world_cam.inverse();
    for (const auto& p : batch.points) {
      const Eigen::Vector3d q = T_cam_world * p.cast<double>();
      scan->push_back(static_cast<float>(q.x()), static_cast<float>(q.y()), static_cast<float>(q.z()));
    }
    const Eigen::Quaterniond r(T_world_cam.linear());
    const octomap::pose6d pose(octomath::Vector3(position.x(), position.y(), position.z()),
                               octomath::Quaternion(r.w(), r.x(), r.y(), r.z()));
    graph.addNode(scan, pose);  // the graph owns the scan
  }
  if (!graph.writeBinary(argv[1])) {
    std::fprintf(stderr, "cannot write %s\n", argv[1]);
    return 1;
  }
  return 0;
}
