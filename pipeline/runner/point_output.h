// point_output.h: where the runner's fused points go on disk: points.ply, streamed, or points.pcd.
// The extension decides: .ply (ply_io.h) or .pcd (PCL's PCD, pcd_io.h); anything else is refused.
// PLY with voxel_m = 0: every point is appended to the file as it comes (memory stays constant
// whatever the sequence length). With voxel_m > 0 one point per voxel is kept (the first seen),
// so memory grows with the surveyed surface, not with the number of frames; the file is written
// at close(). PCD is written at close() by PCL, whose writer takes the whole cloud: with voxel_m = 0
// memory grows with every point (15 bytes each until close(), then PCL's 32 bytes each).
// Units: metres, world frame. Threads: one thread.
#pragma once

#include <memory>
#include <string>
#include <unordered_map>

#include "common/point_batch.h"
#include "io/cloud/ply_io.h"

namespace cenote::pipeline {

class PointOutput {
 public:
  // @throws cenote::Error when the extension is neither .ply nor .pcd, or the file cannot be created.
  PointOutput(const std::string& path, double voxel_m);
  void append(const PointBatch& batch);
  // @throws cenote::Error when the file cannot be written.
  void close();
  size_t pointsWritten() const { return written_; }

 private:
  struct Voxel {
    Eigen::Vector3f point;
    std::array<uint8_t, 3> color;
  };
  std::string path_;
  double voxel_m_;
  std::unique_ptr<io::PlyWriter> writer_;  // null for PCD
  PointBatch pcd_points_;                  // PCD with voxel_m = 0: everything until close()
  std::unordered_map<uint64_t, Voxel> voxels_;
  size_t written_ = 0;
  bool closed_ = false;
};

}  // namespace cenote::pipeline
