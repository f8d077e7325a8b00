#include "bench/integration_peers.h"

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string_view>

#include "common/atomic_file.h"
#include "common/cpu_clock.h"
#include "tests/mapping/support/voxel_sets.h"

namespace cenote::bench {
namespace {

// Wall and CPU time of run() (cpuMs: processCpuMs or threadCpuMs), per frame of `frames`.
template <typename Run>
IntegrationTime timePerFrame(size_t frames, double (*cpuMs)(), Run&& run) {
  const auto t0 = std::chrono::steady_clock::now();
  const double c0 = cpuMs();
  run();
  const double cpu = cpuMs() - c0;
  const double wall = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return {wall / frames, cpu / frames};
}

}  // namespace

IntegrationTime timeOurIntegration(const std::vector<PointBatch>& frames, const mapping::MapConfig& config,
                                   std::unique_ptr<mapping::OccupancyMap>& map) {
  map = std::make_unique<mapping::OccupancyMap>(config);
  map->integrate(frames[0]);  // warm-up: scratch allocation, then start again
  map->reset();
  return timePerFrame(frames.size(), processCpuMs, [&] {
    for (const auto& f : frames) map->integrate(f);
  });
}

IntegrationTime timeProjectiveIntegration(const std::vector<mapping::DepthFrame>& frames, const mapping::MapConfig& config,
                                          std::unique_ptr<mapping::OccupancyMap>& map) {
  map = std::make_unique<mapping::OccupancyMap>(config);
  map->integrateDepth(frames[0]);  // warm-up, as above
  map->reset();
  return timePerFrame(frames.size(), processCpuMs, [&] {
    for (const auto& f : frames) map->integrateDepth(f);
  });
}

IntegrationTime timeOctomapIntegration(const std::vector<PointBatch>& frames, double max_range_m, octomap::OcTree& tree) {
  tree.setProbHit(0.7);
  tree.setProbMiss(0.4);
  tree.setClampingThresMin(0.12);
  tree.setClampingThresMax(0.97);
  std::vector<octomap::Pointcloud> clouds;
  for (const auto& f : frames) clouds.push_back(mapping::test::toOctomap(f));
  return timePerFrame(frames.size(), threadCpuMs, [&] {
    for (size_t i = 0; i < frames.size(); ++i) {
      const Eigen::Vector3d& o = frames[i].origin;
      tree.insertPointCloud(clouds[i], octomap::point3d(o.x(), o.y(), o.z()), max_range_m, false, true);
    }
  });
}

void writeDepthFrames(const std::string& dir, const std::vector<mapping::DepthFrame>& frames, double voxel_m,
                      double max_range_m) {
  std::filesystem::create_directories(dir);
  std::string index;
  char line[512];
  const mapping::DepthFrame& first = frames.front();
  std::snprintf(line, sizeof line, "camera %d %d %.17g %.17g %.17g %.17g\nvoxel_m %.17g\nmax_range_m %.17g\n", first.width,
                first.height, first.fx, first.fy, first.cx, first.cy, voxel_m, max_range_m);
  index += line;
  for (size_t f = 0; f < frames.size(); ++f) {
    std::vector<float> depth = frames[f].depth_m;
    for (float& d : depth) d = d > 0.0f && std::isfinite(d) ? d : 0.0f;
    const std::string name = "depth_" + std::to_string(f) + ".f32";
    writeFileAtomically(dir + "/" + name,
                        std::string_view(reinterpret_cast<const char*>(depth.data()), depth.size() * sizeof(float)),
                        Durability::kFast);
    index += "frame " + name;
    const Eigen::Matrix4d T = frames[f].T_world_cam.matrix();
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 4; ++c) {
        std::snprintf(line, sizeof line, " %.17g", T(r, c));
        index += line;
      }
    }
    index += "\n";
  }
  writeFileAtomically(dir + "/frames.txt", index, Durability::kFast);
}

}  // namespace cenote::bench
