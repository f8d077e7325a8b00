#include "mapping/history/map_history.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <exception>

#include "common/error.h"
#include "mapping/detail/block_table.h"
#include "mapping/history/block_replay.h"
#include "io/compression/zstd_block.h"
#include "mapping/history/frame_codec.h"
#include "mapping/history/frame_resample.h"

namespace cenote::mapping {
namespace {

using history::FrameMeta;
using history::FramePoints;
using history::FrameUpdates;

// Fast compression: a frame is stored on the ingest path (zstd_block.h says what it costs).
constexpr int kCompressionLevel = io::kZstdFastLevel;
constexpr double kSameTime_s = 1e-6;  // a corrected pose at a frame's own time

// The batch's points rounded in the camera frame, and the batch that integrates them.
void quantise(const PointBatch& batch, const Eigen::Isometry3d& T_world_cam, double quantum_m, FramePoints& points,
              PointBatch& rounded) {
  const Eigen::Isometry3d T_cam_world = T_world_cam.inverse();
  points.quantised.resize(batch.points.size());
  rounded.t_s = batch.t_s;
  rounded.origin = batch.origin;
  rounded.points.resize(batch.points.size());
  for (size_t i = 0; i < batch.points.size(); ++i) {
    const Eigen::Vector3d p_cam = T_cam_world * batch.points[i].cast<double>();
    for (int k = 0; k < 3; ++k) points.quantised[i][k] = history::quantisedCoordinate(p_cam[k], quantum_m);
    rounded.points[i] = history::toWorld(T_world_cam, points.quantised[i], quantum_m);
  }
  points.colors = batch.colors;
  rounded.colors = batch.colors;
}

// The pose at t_s from ascending samples: one within kSameTime_s, or the two around t_s at most
// max_gap_s apart (linear in translation, slerp in rotation); false otherwise.
bool poseAt(std::span<const CorrectedPose> poses, double t_s, double max_gap_s, Eigen::Isometry3d& out) {
  const auto after = std::lower_bound(poses.begin(), poses.end(), t_s,
                                      [](const CorrectedPose& p, double t) { return p.t_s < t; });
  if (after != poses.end() && after->t_s - t_s <= kSameTime_s) {
    out = after->T_world_pose;
    return true;
  }
  if (after != poses.begin() && t_s - std::prev(after)->t_s <= kSameTime_s) {
    out = std::prev(after)->T_world_pose;
    return true;
  }
  if (after == poses.end() || after == poses.begin()) return false;
  const CorrectedPose& a = *std::prev(after);
  const CorrectedPose& b = *after;
  if (b.t_s - a.t_s > max_gap_s) return false;
  const double u = (t_s - a.t_s) / (b.t_s - a.t_s);
  const Eigen::Quaterniond qa(a.T_world_pose.linear()), qb(b.T_world_pose.linear());
  out = Eigen::Isometry3d::Identity();
  out.linear() = qa.slerp(u, qb).toRotationMatrix();
  out.translation() = (1.0 - u) * a.T_world_pose.translation() + u * b.T_world_pose.translation();
  return true;
}

void checkPoses(std::span<const CorrectedPose> poses) {
  for (size_t i = 0; i < poses.size(); ++i) {
    const Eigen::Matrix4d& m = poses[i].T_world_pose.matrix();
    const Eigen::Matrix3d R = m.topLeftCorner<3, 3>();
    const std::string where = "correction: pose " + std::to_string(i) + " (t = " + std::to_string(poses[i].t_s) + " s)";
    if (!std::isfinite(poses[i].t_s) || !m.allFinite()) throw Error(where + " must be finite");
    if (!(R.transpose() * R).isIdentity(1e-6) || std::fabs(R.determinant() - 1.0) > 1e-6) {
      throw Error(where + " must be a rigid transform (its rotation is not orthonormal with determinant 1)");
    }
    if (i > 0 && !(poses[i].t_s > poses[i - 1].t_s)) {
      throw Error(where + " must come after the previous pose (t = " + std::to_string(poses[i - 1].t_s) + " s)");
    }
  }
}

// A moved frame's updates at its new pose, before the store and the index take them.
struct MovedFrame {
  bool in_store = false;           // false: dropped (budget) or cleared since the plan
  history::FrameMeta meta;         // with the new pose
  std::string updates_bytes;       // the new updates, encoded
  std::vector<uint64_t> old_keys;  // the blocks it touched at the old pose
  std::vector<uint64_t> new_keys;  // ... and at the new one
  std::exception_ptr error;
};

// Marches moved frame `seq` at its new pose (reads the store, writes nothing but `out` and the
// scratch). Its points go from the store's bytes straight to the world at the new pose, checked by
// their box (each is an integer point of the camera posed rigidly: no NaN can arise).
void marchMoved(const history::FrameStore& store, const OccupancyMap& map, uint32_t seq,
                const Eigen::Isometry3d& T_world_cam, MoveScratch& scratch, int num_threads, MovedFrame& out) {
  try {
    if (!store.contains(seq)) return;
    out.in_store = true;
    const MapConfig& config = map.config();
    const std::string where = "frame " + std::to_string(seq);
    out.old_keys = history::decodeUpdates(store.readUpdates(seq), where, {}).others;  // the keys alone
    out.meta = store.meta(seq);
    out.meta.T_world_cam = out.meta.T_world_cam_marched = T_world_cam;
    PointBatch& batch = scratch.batch;
    batch.t_s = out.meta.t_s;
    batch.origin = T_world_cam * out.meta.origin_cam;
    const Eigen::AlignedBox3f box = history::decodePointsPosed(store.readPoints(seq), where, T_world_cam,
                                                               config.history_quantum_m, scratch.raw, batch);
    map.checkBatch(batch, box);
    scratch.rays.build(batch, config.voxel_size_m, config.max_range_m, num_threads, config.ray_stop_run);
    FrameUpdates updates = FrameUpdates::of(scratch.rays.updates());
    out.updates_bytes = history::encodeUpdates(updates, kCompressionLevel);
    out.new_keys = std::move(updates.keys);
  } catch (...) {
    out.error = std::current_exception();
  }
}

// Moves frame `seq` by resampling its last march's updates to its new pose (frame_resample.h):
// always from those and their pose, so that corrections after one another do not pile up
// resampling errors (reads the store, writes nothing but `out`). Its points are not read.
void resampleMoved(const history::FrameStore& store, const MapConfig& config, uint32_t seq,
                   const Eigen::Isometry3d& T_world_cam, MovedFrame& out) {
  try {
    if (!store.contains(seq)) return;
    out.in_store = true;
    const std::string where = "frame " + std::to_string(seq);
    const history::FrameUpdates marched = history::decodeUpdates(store.readMarched(seq), where);
    out.old_keys = store.isResampled(seq) ? history::decodeUpdates(store.readUpdates(seq), where, {}).others : marched.keys;
    out.meta = store.meta(seq);
    out.meta.T_world_cam = T_world_cam;
    history::FrameUpdates updates = history::resampleUpdates(marched, T_world_cam * out.meta.T_world_cam_marched.inverse(),
                                                             T_world_cam * out.meta.origin_cam, config.voxel_size_m);
    out.updates_bytes = history::encodeUpdates(updates, kCompressionLevel);
    out.new_keys = std::move(updates.keys);
  } catch (...) {
    out.error = std::current_exception();
  }
}

}  // namespace

MapHistory::MapHistory(OccupancyMap& map)
    : map_(map), store_(map.config().history_dir, static_cast<uint64_t>(map.config().history_max_mb) << 20) {}

MapHistory::~MapHistory() = default;

MapDelta MapHistory::integrate(const PointBatch& batch, const Eigen::Isometry3d& T_world_cam,
                               const Eigen::Isometry3d& T_pose_cam) {
  if (!T_world_cam.matrix().allFinite() || !T_pose_cam.matrix().allFinite()) {
    throw Error("map history: the camera pose of the frame at t = " + std::to_string(batch.t_s) + " s must be finite");
  }
  FrameMeta meta;
  meta.t_s = batch.t_s;
  meta.correctable = true;
  meta.T_world_cam = T_world_cam;
  meta.T_pose_cam = T_pose_cam;
  return integrateStored(batch, meta);
}

MapDelta MapHistory::integrate(const PointBatch& batch) {
  FrameMeta meta;
  meta.t_s = batch.t_s;
  meta.T_world_cam.translation() = batch.origin;
  return integrateStored(batch, meta);
}

MapDelta MapHistory::integrateStored(const PointBatch& batch, const FrameMeta& given) {
  map_.checkBatch(batch);
  FrameMeta meta = given;
  meta.T_world_cam_marched = meta.T_world_cam;  // a frame is first stored as marched at its pose
  meta.origin_cam = meta.T_world_cam.inverse() * batch.origin;
  FramePoints points;
  PointBatch rounded;
  quantise(batch, meta.T_world_cam, map_.config().history_quantum_m, points, rounded);
  RayBatch& rays = scratch(0).rays;
  MapDelta delta = map_.integrate(rounded, rays);
  const FrameUpdates updates = FrameUpdates::of(rays.updates());
  const uint32_t seq = next_seq_++;
  store_.put(seq, meta, history::encodePoints(points, kCompressionLevel),
             history::encodeUpdates(updates, kCompressionLevel));
  index(seq, updates.keys);
  enforceBudget();
  return delta;
}

void MapHistory::index(uint32_t seq, const std::vector<uint64_t>& keys) {
  for (uint64_t key : keys) {
    if (sealed_.count(key) != 0) continue;  // never replayed
    std::vector<uint32_t>& frames = frames_of_block_[key];
    frames.insert(std::upper_bound(frames.begin(), frames.end(), seq), seq);
  }
}

void MapHistory::unindex(uint32_t seq, const std::vector<uint64_t>& keys) {
  for (uint64_t key : keys) {
    const auto it = frames_of_block_.find(key);
    if (it == frames_of_block_.end()) continue;
    std::vector<uint32_t>& frames = it->second;
    const auto at = std::lower_bound(frames.begin(), frames.end(), seq);
    if (at != frames.end() && *at == seq) frames.erase(at);
    if (frames.empty()) frames_of_block_.erase(it);
  }
}

void MapHistory::enforceBudget() {
  for (uint32_t seq : store_.overBudget()) {
    const FrameUpdates updates = history::decodeUpdates(store_.readUpdates(seq), "frame " + std::to_string(seq), {});
    for (uint64_t key : updates.others) {
      sealed_.insert(key);
      frames_of_block_.erase(key);  // never replayed now
    }
    store_.erase(seq);
  }
}

void MapHistory::seal(std::span<const BlockIndex> blocks) {
  for (const BlockIndex& block : blocks) {
    if (!detail::inPackRange(block)) continue;
    const uint64_t key = detail::packIndex(block);
    sealed_.insert(key);
    frames_of_block_.erase(key);  // never replayed now
  }
}

void MapHistory::releaseScratch() { moves_ = {}; }

void MapHistory::clear() {
  store_.clear();
  frames_of_block_ = {};
  sealed_ = {};
  releaseScratch();
}

CorrectionPlan MapHistory::planCorrection(std::span<const CorrectedPose> poses) {
  checkPoses(poses);
  CorrectionPlan plan;
  if (poses.empty()) return plan;
  const MapConfig& config = map_.config();
  const double min_turn_rad = config.correction_min_turn_deg * M_PI / 180.0;
  store_.forEach([&](uint32_t seq, const FrameMeta& meta) {
    if (!meta.correctable || meta.t_s < poses.front().t_s - kSameTime_s || meta.t_s > poses.back().t_s + kSameTime_s) {
      return;
    }
    Eigen::Isometry3d T_world_pose;
    if (!poseAt(poses, meta.t_s, config.correction_max_gap_s, T_world_pose)) return;
    const Eigen::Isometry3d T_world_cam = T_world_pose * meta.T_pose_cam;
    const double shift = (T_world_cam.translation() - meta.T_world_cam.translation()).norm();
    const double turn = Eigen::AngleAxisd(meta.T_world_cam.linear().transpose() * T_world_cam.linear()).angle();
    if (shift > config.correction_min_shift_m || turn > min_turn_rad) plan.moved.emplace_back(seq, T_world_cam);
  });
  return plan;
}

MoveScratch& MapHistory::scratch(int slot) {
  if (moves_.size() <= static_cast<size_t>(slot)) moves_.resize(slot + 1);
  return moves_[slot];
}

int MapHistory::numThreads() const {
  const int n = map_.config().num_threads;
  return std::max(1, n > 0 ? n : omp_get_max_threads());
}

size_t MapHistory::movesAtOnce() const { return static_cast<size_t>(numThreads()); }

size_t MapHistory::movesPerStep() const {
  return map_.config().correction_move == CorrectionMove::kResample ? movesAtOnce() : 1;
}

void MapHistory::moveFrame(CorrectionPlan& plan, size_t i) { moveFrames(plan, i, i + 1); }

void MapHistory::moveFrames(CorrectionPlan& plan, size_t begin, size_t end) {
  end = std::min(end, plan.moved.size());
  if (begin >= end) return;
  const int threads = numThreads();
  const int n = static_cast<int>(end - begin);
  // A move is independent of the map, and its result of the thread count: frames are moved side by
  // side, one thread each (which spends less time in a march's serial parts than all threads on one
  // frame after the other); a lone frame's march has all the threads (a resampling is one thread's
  // work). (Nested OpenMP is off, so a march inside the parallel loop would run on one thread
  // whatever it was given.)
  const int side_by_side = std::min(n, threads);
  const int each = side_by_side > 1 ? 1 : threads;
  const bool resample = map_.config().correction_move == CorrectionMove::kResample;
  if (!resample) {
    for (int slot = 0; slot < side_by_side; ++slot) scratch(slot);  // a resampling needs none
  }
  std::vector<MovedFrame> moved(n);
#pragma omp parallel for num_threads(side_by_side) schedule(dynamic, 1)
  for (int k = 0; k < n; ++k) {
    const auto& [seq, T_world_cam] = plan.moved[begin + k];
    if (resample) {
      resampleMoved(store_, map_.config(), seq, T_world_cam, moved[k]);
    } else {
      marchMoved(store_, map_, seq, T_world_cam, scratch(omp_get_thread_num()), each, moved[k]);
    }
  }
  // In plan order, as moveFrame one after the other would.
  for (int k = 0; k < n; ++k) {
    MovedFrame& m = moved[k];
    if (m.error) std::rethrow_exception(m.error);
    if (!m.in_store) continue;  // its blocks are sealed
    const uint32_t seq = plan.moved[begin + k].first;
    if (resample) {
      store_.putResampled(seq, m.meta, m.updates_bytes);
    } else {
      store_.putUpdates(seq, m.meta, m.updates_bytes);
    }
    unindex(seq, m.old_keys);
    index(seq, m.new_keys);
    plan.affected.insert(m.old_keys.begin(), m.old_keys.end());
    plan.affected.insert(m.new_keys.begin(), m.new_keys.end());
  }
}

CorrectionSummary MapHistory::correct(std::span<const CorrectedPose> poses) {
  CorrectionPlan plan = planCorrection(poses);
  for (size_t i = 0; i < plan.moved.size(); i += movesAtOnce()) moveFrames(plan, i, i + movesAtOnce());
  return finishCorrection(plan);
}

CorrectionSummary MapHistory::finishCorrection(CorrectionPlan& plan) {
  CorrectionSummary summary;
  summary.frames_moved = plan.moved.size();
  if (plan.affected.empty()) return summary;
  const std::unordered_set<uint64_t>& affected = plan.affected;

  // 3. Rebuild the affected blocks no dropped frame touched, from unknown, by replaying in order
  // every frame that touches them.
  std::vector<uint64_t> keys;
  keys.reserve(affected.size());
  for (uint64_t key : affected) {
    if (sealed_.count(key) != 0) {
      ++summary.blocks_kept;
    } else {
      keys.push_back(key);
    }
  }
  std::sort(keys.begin(), keys.end());
  std::vector<uint32_t> frames;
  for (uint64_t key : keys) {
    const auto it = frames_of_block_.find(key);
    if (it != frames_of_block_.end()) frames.insert(frames.end(), it->second.begin(), it->second.end());
  }
  std::sort(frames.begin(), frames.end());
  frames.erase(std::unique(frames.begin(), frames.end()), frames.end());
  summary.frames_replayed = frames.size();

  // 4. Swap them in.
  const std::vector<BlockState> states = history::replayBlocks(store_, frames, keys, map_.model(),
                                                               map_.config().num_threads);
  summary.blocks_rebuilt = states.size();
  summary.delta = map_.replaceBlocks(states);
  return summary;
}

}  // namespace cenote::mapping
