#include "pipeline/runner/point_output.h"

#include <cmath>

namespace cenote::pipeline {
namespace {

// 21 bits per axis: +-1048576 voxels around the origin (+-10 km at 1 cm).
uint64_t voxelKey(const Eigen::Vector3f& p, double voxel_m) {
  auto axis = [&](float v) { return static_cast<uint64_t>(static_cast<int64_t>(std::floor(v / voxel_m)) & 0x1FFFFF); };
  return axis(p.x()) | (axis(p.y()) << 21) | (axis(p.z()) << 42);
}

}  // namespace

PointOutput::PointOutput(const std::string& path, double voxel_m)
    : voxel_m_(voxel_m), writer_(std::make_unique<io::PlyWriter>(path)) {}

void PointOutput::append(const PointBatch& batch) {
  if (voxel_m_ <= 0.0) {
    writer_->append(batch);
    written_ += batch.size();
    return;
  }
  const std::array<uint8_t, 3> grey = {128, 128, 128};
  for (size_t i = 0; i < batch.size(); ++i) {
    voxels_.try_emplace(voxelKey(batch.points[i], voxel_m_), Voxel{batch.points[i], batch.hasColor() ? batch.colors[i] : grey});
  }
}

void PointOutput::close() {
  if (voxel_m_ > 0.0) {
    PointBatch all;
    all.points.reserve(voxels_.size());
    all.colors.reserve(voxels_.size());
    for (const auto& [key, voxel] : voxels_) {
      all.points.push_back(voxel.point);
      all.colors.push_back(voxel.color);
    }
    writer_->append(all);
    written_ = all.size();
  }
  writer_->close();
}

}  // namespace cenote::pipeline
