// point_batch.h: coloured points in the world frame, as handed from the pipeline to the map.
// Units: metres. Frame: world (points and origin alike). Colours: 8-bit RGB.
// The origin is the optical centre of the camera that saw the points: the map casts a ray from it
// to each point (free space along the ray, a hit at its end).
// Threads: a plain value; no sharing rules beyond those of std::vector.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

namespace cenote {

struct PointBatch {
  double t_s = 0.0;                                  // time of the frame the points come from
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  // camera centre in the world frame
  std::vector<Eigen::Vector3f> points;               // world frame
  std::vector<std::array<uint8_t, 3>> colors;        // RGB, one per point; empty when uncoloured

  size_t size() const { return points.size(); }
  bool empty() const { return points.empty(); }
  bool hasColor() const { return !colors.empty(); }
  // Keeps the capacity, so that a batch reused frame after frame stops allocating.
  void clear() {
    points.clear();
    colors.clear();
  }
};

}  // namespace cenote
