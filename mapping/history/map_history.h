// map_history.h: a map that follows pose corrections (loop closures). Every frame integrated
// through it is kept in a bounded, disk-backed FrameStore (its points, rounded relative to the
// camera, and the voxel updates its integration made), and a per-block index records which frames
// touched which blocks. correct() takes corrected poses of past frames and re-shapes the map:
//  1. each frame whose pose moved (map.correction_min_shift_m / _turn_deg) gets new updates at its
//     new pose, which replace its old ones in the store, in one of two ways (map.correction_move):
//     - march (the default): its rays marched again at its new pose from its stored points (a
//       frame's integration and more: decoding its points);
//     - resample: the updates of its last ray march moved rigidly to the new pose
//       (frame_resample.h: free voxels pulled through the move, hits pushed), always from those
//       marched updates and their pose, which the store keeps, so that corrections after one
//       another do not pile up resampling errors; no ray marched, its points not read;
//  2. every block the moved frames touched, at the old pose or the new, is rebuilt from unknown by
//     replaying the stored updates of every frame that touches it, in the original order,
//     restricted to those blocks (no ray is marched for a frame that did not move; block_replay.h);
//  3. the rebuilt blocks are swapped in (OccupancyMap::replaceBlocks: a reader sees each block old
//     or new, never a mix).
// Why this design: log-odds are clamped, so a frame's contribution cannot be subtracted; replaying
// a block's frames in order gives exactly the value a map built from scratch with the corrected
// poses holds there, given each frame's updates at its corrected pose. With the march those are
// exact: the updates a frame made inside a block are exactly its updates restricted to the block
// (the stored masks are the whole frame's, after the ray march's early stop), so each rebuilt block
// equals the from-scratch block voxel for voxel, colours included
// (tests/mapping/history/map_history_test.cpp). With the resampling a moved frame's updates differ
// from its march at the new pose only within about a voxel of the boundaries of its free and hit
// sets, and frames that did not move are replayed exactly: with dense depth (correction_bench's
// tunnel, 300 of 1500 frames moved) the map agrees with the one built from scratch in 99.8 % of
// the known voxels (the bar: 99 %), but where free space is ragged (rays about a voxel
// apart, sparse stereo: the simulated cave of cli_corrections_test at 320x240) in 91 %, which is
// why the march is the default (docs/CORRECTIONS.md). The cost grows with the frames that moved (a
// resampling or a ray march each) and the frames touching the affected blocks (a decompression and a
// mask merge each), not with the length of the dive. Submaps per keyframe were the alternative: no
// store, but a query would fuse overlapping submaps, and the answer is not the single map's.
// Limits: frames dropped from the store (its budget, map.history_max_mb) cannot be replayed; a
// block that one of them touched keeps its state in a correction (counted in blocks_kept). Points
// are integrated as rounded (map.history_quantum_m, 1 mm by default), so that a replay sees the
// same points as the first integration. A fused frame is moved rigidly with its reference pose.
// Clearing or cropping the map is not replayed: seal() the blocks they changed; call clear() after
// reset().
// Units: metres, seconds. Frames: world; T_world_pose is whatever frame the corrections give poses
// of (e.g. the raw left camera), T_pose_cam the integrated camera in it.
// Threads: one writer (integrate, correct, clear), the same that writes the map; the map's readers
// may read at any time.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "common/point_batch.h"
#include "mapping/history/frame_store.h"
#include "mapping/integration/ray_batch.h"
#include "mapping/occupancy_map.h"

namespace cenote::mapping {

// A corrected pose: T_world_pose at t_s.
struct CorrectedPose {
  double t_s = 0.0;
  Eigen::Isometry3d T_world_pose = Eigen::Isometry3d::Identity();
};

struct CorrectionSummary {
  size_t frames_moved = 0;     // frames whose pose changed beyond the thresholds
  size_t frames_replayed = 0;  // frames whose stored updates were replayed into the rebuilt blocks
  size_t blocks_rebuilt = 0;
  size_t blocks_kept = 0;  // affected blocks left as they were: a frame dropped from the store touched them
  MapDelta delta;          // blocks that changed
};

// A correction in steps (MapHistory::planCorrection): the frames that move, with their new camera
// poses, and the blocks the frames moved so far touched.
struct CorrectionPlan {
  std::vector<std::pair<uint32_t, Eigen::Isometry3d>> moved;
  std::unordered_set<uint64_t> affected;  // detail::packIndex of the blocks
};

// The scratch of one frame marched at a time (MapHistory::moveFrames): its ray march, its points.
struct MoveScratch {
  RayBatch rays;
  PointBatch batch;
  std::string raw;  // the points' decompressed bytes
};

class MapHistory {
 public:
  // The store follows map.config(): history_max_mb, history_dir, history_quantum_m.
  // @throws IoError when the store's folder cannot be made.
  explicit MapHistory(OccupancyMap& map);
  ~MapHistory();

  // Integrates `batch` as OccupancyMap::integrate does, its points rounded to history_quantum_m in
  // the camera frame T_world_cam, and stores the frame. T_pose_cam: the camera in the frame the
  // corrections' poses are of (identity when they are camera poses).
  // @throws what OccupancyMap::integrate throws (map and store unchanged), and IoError /
  //   ResourceExhaustedError from the store (the map then holds the frame, the store does not).
  MapDelta integrate(const PointBatch& batch, const Eigen::Isometry3d& T_world_cam,
                     const Eigen::Isometry3d& T_pose_cam = Eigen::Isometry3d::Identity());
  // A batch without a camera pose (points streamed straight to the map): stored, so replays keep
  // it, but never moved by a correction.
  MapDelta integrate(const PointBatch& batch);

  // Applies corrected poses (ascending strictly in t_s): every stored frame whose time they cover
  // (a sample within 1 microsecond, or two at most correction_max_gap_s apart around it,
  // interpolated) takes T_world_pose * T_pose_cam as its new camera pose; see 1.-3. above.
  // @throws Error, changing nothing, for poses not ascending or not finite rigid transforms.
  CorrectionSummary correct(std::span<const CorrectedPose> poses);

  // correct() in steps, so that a writer can integrate new frames between them (MapHost does):
  // the plan (which frames move; @throws as correct()), the moves (1. above), then the replay and
  // swap. Frames integrated between the steps are replayed too where they touch the affected
  // blocks, so the result is the same as correct() after them. Steps of one plan run in order on
  // the writer, and no other correction starts before its finishCorrection().
  // moveFrames moves the frames [begin, end) side by side (up to map.num_threads at once, one
  // thread each; a lone frame's march on all of them; the same result as moveFrame of each in
  // order); correct() takes movesAtOnce() of them per step. Steps between which ingest goes on
  // (MapHost) take movesPerStep(): as many when resampling (one thread's work of a few ms a
  // frame), one when marching (a lone frame's march uses every thread: an ingest frame then waits
  // for one frame's march at most).
  // @throws IoError from the store, the frames before the failing one moved.
  CorrectionPlan planCorrection(std::span<const CorrectedPose> poses);
  void moveFrame(CorrectionPlan& plan, size_t i);
  void moveFrames(CorrectionPlan& plan, size_t begin, size_t end);
  CorrectionSummary finishCorrection(CorrectionPlan& plan);
  size_t movesAtOnce() const;
  size_t movesPerStep() const;

  // Forgets every stored frame (after OccupancyMap::reset()).
  void clear();
  // Marks blocks whose state came from elsewhere than the stored frames (a loaded map, a clear or
  // crop): corrections keep them as they are (counted in blocks_kept).
  void seal(std::span<const BlockIndex> blocks);
  // Frees the ray-marching scratch, whose capacity the largest frame so far set (after a crop,
  // as OccupancyMap frees its own); the next frame allocates it again.
  void releaseScratch();

  size_t numFrames() const { return store_.numFrames(); }
  uint64_t storeBytes() const { return store_.bytes(); }
  const history::FrameStore& store() const { return store_; }

 private:
  MapDelta integrateStored(const PointBatch& batch, const history::FrameMeta& meta);
  // The scratch of the slot-th frame moved side by side; slot 0's rays are also integrate()'s.
  MoveScratch& scratch(int slot);
  void index(uint32_t seq, const std::vector<uint64_t>& keys);
  void unindex(uint32_t seq, const std::vector<uint64_t>& keys);
  void enforceBudget();
  int numThreads() const;

  OccupancyMap& map_;
  history::FrameStore store_;
  std::vector<MoveScratch> moves_;  // moveFrames' (slot 0's ray march also integrate()'s)
  uint32_t next_seq_ = 0;
  std::unordered_map<uint64_t, std::vector<uint32_t>> frames_of_block_;  // ascending seqs
  std::unordered_set<uint64_t> sealed_;                                  // blocks a dropped frame touched
};

}  // namespace cenote::mapping
