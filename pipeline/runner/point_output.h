// point_output.h: where the runner's fused points go on disk: points.ply, streamed.
// With voxel_m = 0 every point is appended to the file as it comes (memory stays constant
// whatever the sequence length). With voxel_m > 0 one point per voxel is kept (the first seen),
// so memory grows with the surveyed surface, not with the number of frames; the file is written
// at close().
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
  // @throws cenote::Error when the file cannot be created.
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
  double voxel_m_;
  std::unique_ptr<io::PlyWriter> writer_;
  std::unordered_map<uint64_t, Voxel> voxels_;
  size_t written_ = 0;
};

}  // namespace cenote::pipeline
