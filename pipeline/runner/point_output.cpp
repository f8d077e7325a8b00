#include "pipeline/runner/point_output.h"

#include <cmath>

#include "common/error.h"
#include "io/cloud/pcd_io.h"

namespace cenote::pipeline {
namespace {

// 21 bits per axis: +-1048576 voxels around the origin (+-10 km at 1 cm).
uint64_t voxelKey(const Eigen::Vector3f& p, double voxel_m) {
  auto axis = [&](float v) { return static_cast<uint64_t>(static_cast<int64_t>(std::floor(v / voxel_m)) & 0x1FFFFF); };
  return axis(p.x()) | (axis(p.y()) << 21) | (axis(p.z()) << 42);
}

bool endsWith(const std::string& s, const std::string& suffix) {
  return s.size() > suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

}  // namespace

PointOutput::PointOutput(const std::string& path, double voxel_m) : path_(path), voxel_m_(voxel_m) {
  if (endsWith(path, ".ply")) {
    writer_ = std::make_unique<io::PlyWriter>(path);
  } else if (!endsWith(path, ".pcd")) {
    throw Error("point output " + path + ": the extension must be .ply or .pcd");
  }
}

void PointOutput::append(const PointBatch& batch) {
  const std::array<uint8_t, 3> grey = {128, 128, 128};
  if (voxel_m_ <= 0.0) {
    if (writer_) {
      writer_->append(batch);
    } else {
      pcd_points_.points.insert(pcd_points_.points.end(), batch.points.begin(), batch.points.end());
      if (batch.hasColor()) {
        pcd_points_.colors.insert(pcd_points_.colors.end(), batch.colors.begin(), batch.colors.end());
      } else {
        pcd_points_.colors.resize(pcd_points_.points.size(), grey);
      }
    }
    written_ += batch.size();
    return;
  }
  for (size_t i = 0; i < batch.size(); ++i) {
    voxels_.try_emplace(voxelKey(batch.points[i], voxel_m_),
                        Voxel{batch.points[i], batch.hasColor() ? batch.colors[i] : grey});
  }
}

void PointOutput::close() {
  if (closed_) return;
  closed_ = true;
  if (voxel_m_ > 0.0) {
    PointBatch all;
    all.points.reserve(voxels_.size());
    all.colors.reserve(voxels_.size());
    for (const auto& [key, voxel] : voxels_) {
      all.points.push_back(voxel.point);
      all.colors.push_back(voxel.color);
    }
    written_ = all.size();
    if (writer_) {
      writer_->append(all);
    } else {
      pcd_points_ = std::move(all);
    }
  }
  if (writer_) {
    writer_->close();
  } else {
    io::writePcd(path_, pcd_points_.points, pcd_points_.colors);
  }
}

}  // namespace cenote::pipeline
