// client_types.h: the plain values the C++ client takes and returns (Eigen and std types only, so
// that a user never needs the generated protobuf headers). They mirror proto/cenote/v1/*.proto
// field for field; the comments there are the contract.
// Units: metres, seconds; frame: the map's world frame. Grid convention (as mapping/voxel_types.h):
// voxel i along an axis covers [i * s, (i + 1) * s) for voxel size s.
// Threads: plain values.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace cenote::client {

// Unknown: never observed (or cleared). Unknown is never free. Values as on the wire.
enum class VoxelState : uint8_t { kUnknown = 0, kFree = 1, kOccupied = 2 };
// "unknown", "free", "occupied".
const char* toString(VoxelState state);

// Axis-aligned box; a voxel belongs to it when its centre does. Empty when any min > max.
struct Box {
  Eigen::Vector3d min_m = Eigen::Vector3d::Constant(1.0);
  Eigen::Vector3d max_m = Eigen::Vector3d::Constant(-1.0);
  bool isEmpty() const { return (min_m.array() > max_m.array()).any(); }
};

struct VoxelResult {
  VoxelState state = VoxelState::kUnknown;
  float probability = 0.5f;  // 0.5 where unknown
};

struct BoxCounts {
  uint64_t unknown = 0;
  uint64_t free = 0;
  uint64_t occupied = 0;
  bool any_occupied = false;
  uint64_t total() const { return unknown + free + occupied; }
};

struct Segment {
  Eigen::Vector3d start_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d end_m = Eigen::Vector3d::Zero();
  double radius_m = 0.0;  // 0: the voxels the segment passes through; > 0: a capsule
};

struct Ray {
  Eigen::Vector3d origin_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d direction = Eigen::Vector3d::UnitX();  // any non-zero length
};

struct Collision {
  bool hit = false;
  double hit_distance_m = 0.0;  // from the start to the hit voxel's centre, along the segment
  Eigen::Vector3i hit_voxel = Eigen::Vector3i::Zero();
  Eigen::Vector3d hit_point_m = Eigen::Vector3d::Zero();  // centre of the hit voxel
  bool crossed_unknown = false;
  double unknown_distance_m = 0.0;
  bool stopped_at_unknown = false;
  bool clear = false;  // safe to travel: no hit and, with stop_at_unknown, no unknown
};

struct DistanceResult {
  double distance_m = 0.0;                             // max_distance_m when nothing is nearer
  Eigen::Vector3d gradient = Eigen::Vector3d::Zero();  // unit, away from the obstacle; zero at max
  bool within_max = false;
};

struct Frontier {
  uint64_t id = 0;
  uint64_t num_voxels = 0;
  Eigen::Vector3d centroid_m = Eigen::Vector3d::Zero();
  Box bounds;
  Eigen::Vector3d direction = Eigen::Vector3d::Zero();  // mean unit direction into the unknown
  double distance_m = 0.0;                              // of the centroid from the query position
};

struct FrontierQuery {
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();  // clusters come sorted by distance from here
  Box region;                                            // only clusters whose centroid lies in it; empty: everywhere
  uint32_t max_clusters = 0;                             // 0: all
};

// Voxels of a box (ExtractVoxels): parallel arrays, one entry per voxel.
struct ExtractedVoxels {
  double voxel_size_m = 0.0;
  std::vector<Eigen::Vector3i> ijk;
  std::vector<VoxelState> states;
  std::vector<float> probabilities;
  std::vector<std::array<uint8_t, 3>> rgb;  // black where a voxel has no colour
  uint64_t map_version = 0;
  size_t size() const { return ijk.size(); }
};

struct MapInfo {
  double voxel_size_m = 0.0;
  std::string frame_id;
  Box bounds;  // of the known voxels; empty map: empty box
  uint64_t occupied = 0;
  uint64_t free = 0;
  double prob_hit = 0.0;
  double prob_miss = 0.0;
  double clamp_min = 0.0;
  double clamp_max = 0.0;
  double occupied_threshold = 0.0;
  double max_range_m = 0.0;
  double max_distance_m = 0.0;
  uint64_t map_version = 0;
};

struct StageTiming {
  std::string name;
  double median_ms = 0.0;
  double p95_ms = 0.0;
  uint64_t count = 0;
};

struct MethodStats {
  std::string method;  // e.g. "Query/GetVoxels"
  uint64_t calls = 0;
  uint64_t errors = 0;
  double p50_ms = 0.0;
  double p99_ms = 0.0;
};

struct ServerStats {
  double uptime_s = 0.0;
  uint64_t frames_received = 0;
  uint64_t frames_processed = 0;
  uint64_t frames_skipped = 0;
  uint64_t frames_rejected = 0;
  uint64_t batches_integrated = 0;
  uint64_t poses_received = 0;
  uint64_t occupied = 0;
  uint64_t free = 0;
  uint64_t map_memory_bytes = 0;
  uint64_t process_memory_bytes = 0;
  uint64_t map_version = 0;
  std::vector<StageTiming> stages;
  std::vector<MethodStats> methods;
  uint64_t subscribers = 0;
  double last_snapshot_age_s = -1.0;  // -1: none yet
};

// As admin.proto's SnapshotFormat (and mapping/io/map_file_format.h, whose table decides): the
// format follows the path's extension, kFromExtension takes it from there, and any other value
// must agree with it (.vdb .bt .ot .mesh.ply .points.ply .pcd; a plain .ply needs kMeshPly or
// kPointsPly).
enum class SnapshotFormat { kFromExtension = 0, kVdb = 1, kBt = 2, kOt = 3, kMeshPly = 4, kPointsPly = 5, kPointsPcd = 6 };

struct SnapshotResult {
  std::string path;  // absolute path written on the server
  uint64_t bytes = 0;
  uint64_t map_version = 0;
};

struct ChangeResult {
  uint64_t changed_blocks = 0;
  Box changed_bounds;
  uint64_t map_version = 0;
};

// Already-fused points in the world frame with the sensor origin they were seen from.
struct PointBatch {
  double timestamp_s = 0.0;
  Eigen::Vector3d origin_m = Eigen::Vector3d::Zero();
  std::vector<Eigen::Vector3d> points_m;
  std::vector<std::array<uint8_t, 3>> rgb;  // empty, or one per point
  size_t size() const { return points_m.size(); }
};

struct BatchAck {
  uint64_t sequence = 0;
  double timestamp_s = 0.0;
  int status_code = 0;  // grpc::StatusCode; 0 (OK) when integrated
  std::string message;
  uint64_t voxels_updated = 0;
  uint64_t changed_blocks = 0;
  uint64_t map_version = 0;
  bool ok() const { return status_code == 0; }
};

// A rigid transform T_world_frame (maps points of the frame into the world).
struct Pose {
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();  // unit
};

// Raw pixels: grey, colour, or a raw colour camera's Bayer mosaic named by its first two rows
// (kBayerRggb8: R G, then G B), which the server demosaics to BGR.
enum class ImageEncoding {
  kUnspecified = 0,
  kMono8 = 1,
  kBgr8 = 2,
  kRgb8 = 3,
  kBayerRggb8 = 4,
  kBayerBggr8 = 5,
  kBayerGbrg8 = 6,
  kBayerGrbg8 = 7
};

// One camera image: encoded (PNG, JPEG: anything OpenCV's imdecode reads) or raw pixels.
struct Image {
  std::string encoded;  // non-empty: an encoded file's bytes; the raw fields are then unused
  uint32_t width = 0;
  uint32_t height = 0;
  ImageEncoding encoding = ImageEncoding::kUnspecified;
  std::string raw;  // rows top to bottom, no padding: width * height * channels bytes
};

// Raw (unrectified) images of the server's calibrated rig.
struct StereoFrame {
  double timestamp_s = 0.0;  // strictly increasing within a stream
  Image left, right;
  bool has_pose = false;  // false: the server matches a streamed pose by timestamp
  Pose T_world_cam;       // of the raw left camera
};

enum class FrameOutcome { kUnspecified = 0, kProcessed = 1, kSkippedNoPose = 2, kSkippedNotKeyframe = 3, kRejected = 4 };

struct FrameAck {
  uint64_t sequence = 0;
  double timestamp_s = 0.0;
  FrameOutcome outcome = FrameOutcome::kUnspecified;
  int status_code = 0;  // grpc::StatusCode; 0 unless rejected
  std::string message;  // why it was skipped or rejected
  uint64_t map_version = 0;
};

struct PoseStamped {
  double timestamp_s = 0.0;  // strictly increasing within a stream
  Pose T_world_cam;          // of the raw left camera
};

struct PoseAck {
  uint64_t sequence = 0;
  double timestamp_s = 0.0;
  int status_code = 0;  // 0: stored; otherwise rejected (NaN, not a rotation, out of order)
  std::string message;
  bool ok() const { return status_code == 0; }
};

// One 8 x 8 x 8 block of a MapUpdate: voxel (i, j, k) of the block is (8 x + i, 8 y + j, 8 z + k),
// at offset 64 i + 8 j + k.
struct UpdateBlock {
  Eigen::Vector3i index = Eigen::Vector3i::Zero();  // block index: voxel index / 8, rounded down
  std::array<VoxelState, 512> states{};             // all unknown: the block was cleared
  std::vector<float> probabilities;                 // 512 when asked for, else empty
};

struct MapUpdate {
  uint64_t sequence = 0;  // the map's version after this change
  bool snapshot = false;  // part of a full-map snapshot
  bool snapshot_complete = false;
  bool resync = false;  // this snapshot replaces everything the subscriber had
  Box changed_bounds;
  double voxel_size_m = 0.0;
  std::vector<UpdateBlock> blocks;
};

struct SubscribeOptions {
  Box region;  // only blocks holding a voxel whose centre lies in it; empty: everywhere
  bool include_probabilities = false;
};

}  // namespace cenote::client
