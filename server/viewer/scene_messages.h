// scene_messages.h: the viewer's channel messages as JSON text (Foxglove's JSON encoding of
// foxglove.SceneUpdate, FrameTransform, PosesInFrame, PointCloud, CompressedImage;
// foxglove_schemas.h), built by
// hand for the map's cubes, which are most of the bytes.
// A map block is the scene entity "block/X/Y/Z" (its block index): one cube per occupied voxel
// (level of detail "full"), or one cube the size of the block, coloured by the mean of its voxels
// ("coarse"). Its metadata says which ("lod"), how many occupied voxels it stands for ("voxels")
// and, at full detail, each cube's occupancy probability ("probabilities": two decimals, comma
// separated, in cube order). A block left without occupied voxels is deleted by that id.
// Units: metres, world frame (frame_id given), times in ns since the Unix epoch.
// Threads: free functions; a SceneUpdateWriter belongs to one thread.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "common/point_batch.h"
#include "mapping/voxel_types.h"

namespace cenote::mapping {
struct FrontierCluster;
}

namespace cenote::server::viewer {

enum class ColorBy { kImage, kHeight };

// The colour of height z_m (a smooth hue cycle every 4 m, so that it needs no range).
std::array<uint8_t, 3> heightColor(double z_m);

struct VoxelCube {
  Eigen::Vector3f centre_m;
  std::array<uint8_t, 3> rgb;
};

std::string blockEntityId(const mapping::BlockIndex& block);

// Writes one SceneUpdate: its deletions and entities, in the order given.
class SceneUpdateWriter {
 public:
  SceneUpdateWriter(uint64_t time_ns, std::string frame_id);
  void deleteEntity(const std::string& id);
  // The block's entity: `cubes` of side cube_m (coarse: one cube of the block's side standing
  // for voxels occupied voxels).
  void blockEntity(const mapping::BlockIndex& block, const std::vector<VoxelCube>& cubes, float cube_m, bool coarse,
                   uint64_t voxels, const std::vector<float>& probabilities);
  // Bytes written so far (the message is about this long).
  size_t size() const { return deletions_.size() + entities_.size() + 64; }
  bool empty() const { return deletions_.empty() && entities_.empty(); }
  std::string finish() const;

  // Bytes of one block entity with n cubes, for planning before writing (an upper bound within a
  // few percent).
  static size_t entityBytes(size_t cubes);

 private:
  std::string stamp_;
  std::string frame_id_;
  std::string deletions_, entities_;
};

// The camera: world -> "camera" (child), from T_world_cam.
std::string frameTransformJson(uint64_t time_ns, const std::string& frame_id, const Eigen::Isometry3d& T_world_cam);
// The camera centres and orientations so far.
std::string posesInFrameJson(uint64_t time_ns, const std::string& frame_id, const std::vector<Eigen::Isometry3d>& poses);
// Points as x y z float32 and r g b uint8 (PackedElementField types 7 and 1), stride 15.
std::string pointCloudJson(uint64_t time_ns, const std::string& frame_id, const PointBatch& batch);
// A JPEG file seen from the frame "camera" (the child of frameTransformJson).
std::string compressedImageJson(uint64_t time_ns, const std::string& jpeg);
// Frontier clusters: per cluster, a translucent box (its bounds), a sphere at its centroid and an
// arrow into the unknown; entity "frontier/<id>"; every earlier frontier entity deleted first.
std::string frontierSceneJson(uint64_t time_ns, const std::string& frame_id,
                              const std::vector<mapping::FrontierCluster>& clusters);

}  // namespace cenote::server::viewer
