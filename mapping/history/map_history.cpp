#include "mapping/history/map_history.h"

#include <algorithm>
#include <cmath>

#include "common/error.h"
#include "mapping/detail/block_table.h"
#include "mapping/detail/publish_word.h"
#include "mapping/history/frame_codec.h"

namespace cenote::mapping {
namespace {

using history::FrameMeta;
using history::FramePoints;
using history::FrameUpdates;

// Fast deflate: a frame is stored on the ingest path (level 1 is within 10 % of level 6's size
// on the masks, which are most of a frame's bytes, at a third of the time).
constexpr int kDeflateLevel = 1;
constexpr double kSameTime_s = 1e-6;  // a corrected pose at a frame's own time

Eigen::Vector3f toWorld(const Eigen::Isometry3d& T_world_cam, const Eigen::Vector3i& q, double quantum_m) {
  return (T_world_cam * (q.cast<double>() * quantum_m)).cast<float>();
}

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
    for (int k = 0; k < 3; ++k) points.quantised[i][k] = static_cast<int>(std::llround(p_cam[k] / quantum_m));
    rounded.points[i] = toWorld(T_world_cam, points.quantised[i], quantum_m);
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

// A block being rebuilt: its voxels and the colours of its hit voxels.
struct RebuiltBlock {
  BlockView view;
  std::unordered_map<int, std::pair<std::array<uint8_t, 3>, int>> colors;  // offset -> mean, count
};

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
  meta.origin_cam = meta.T_world_cam.inverse() * batch.origin;
  FramePoints points;
  PointBatch rounded;
  quantise(batch, meta.T_world_cam, map_.config().history_quantum_m, points, rounded);
  MapDelta delta = map_.integrate(rounded, rays_);
  const FrameUpdates updates = FrameUpdates::of(rays_.updates());
  const uint32_t seq = next_seq_++;
  store_.put(seq, meta, history::encodePoints(points, kDeflateLevel), history::encodeUpdates(updates, kDeflateLevel));
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
    const FrameUpdates updates = history::decodeUpdates(store_.readUpdates(seq), "frame " + std::to_string(seq),
                                                        [](uint64_t) { return false; });
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

void MapHistory::releaseScratch() { rays_ = RayBatch(); }

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

void MapHistory::moveFrame(CorrectionPlan& plan, size_t i) {
  const auto& [seq, T_world_cam] = plan.moved.at(i);
  if (!store_.contains(seq)) return;  // dropped (budget) or cleared since the plan: its blocks are sealed
  const MapConfig& config = map_.config();
  const std::string where = "frame " + std::to_string(seq);
  // The old blocks' keys only (all in `others`).
  const FrameUpdates old_updates = history::decodeUpdates(store_.readUpdates(seq), where, [](uint64_t) { return false; });
  const std::string points_bytes = store_.readPoints(seq);
  const FramePoints points = history::decodePoints(points_bytes, where);
  FrameMeta meta = store_.meta(seq);
  PointBatch batch;
  batch.t_s = meta.t_s;
  batch.origin = T_world_cam * meta.origin_cam;
  batch.points.resize(points.quantised.size());
  for (size_t k = 0; k < points.quantised.size(); ++k) {
    batch.points[k] = toWorld(T_world_cam, points.quantised[k], config.history_quantum_m);
  }
  batch.colors = points.colors;
  map_.checkBatch(batch);
  rays_.build(batch, config.voxel_size_m, config.max_range_m, config.num_threads, config.ray_stop_run);
  const FrameUpdates new_updates = FrameUpdates::of(rays_.updates());
  meta.T_world_cam = T_world_cam;
  store_.put(seq, meta, points_bytes, history::encodeUpdates(new_updates, kDeflateLevel));
  unindex(seq, old_updates.others);
  index(seq, new_updates.keys);
  plan.affected.insert(old_updates.others.begin(), old_updates.others.end());
  plan.affected.insert(new_updates.keys.begin(), new_updates.keys.end());
}

CorrectionSummary MapHistory::correct(std::span<const CorrectedPose> poses) {
  CorrectionPlan plan = planCorrection(poses);
  for (size_t i = 0; i < plan.moved.size(); ++i) moveFrame(plan, i);
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
  std::unordered_map<uint64_t, uint32_t> slot_of;
  slot_of.reserve(keys.size());
  for (uint32_t i = 0; i < keys.size(); ++i) slot_of.emplace(keys[i], i);
  std::vector<uint32_t> frames;
  for (uint64_t key : keys) {
    const auto it = frames_of_block_.find(key);
    if (it != frames_of_block_.end()) frames.insert(frames.end(), it->second.begin(), it->second.end());
  }
  std::sort(frames.begin(), frames.end());
  frames.erase(std::unique(frames.begin(), frames.end()), frames.end());
  summary.frames_replayed = frames.size();

  std::vector<RebuiltBlock> rebuilt(keys.size());
  const LogOddsModel& model = map_.model();
  for (uint32_t seq : frames) {
    const FrameUpdates updates = history::decodeUpdates(store_.readUpdates(seq), "frame " + std::to_string(seq),
                                                        [&](uint64_t key) { return slot_of.count(key) != 0; });
    for (size_t b = 0; b < updates.keys.size(); ++b) {
      const auto it = slot_of.find(updates.keys[b]);
      BlockView& view = rebuilt[it->second].view;
      const BlockMasks& masks = updates.masks[b];
      for (int w = 0; w < 8; ++w) {
        const uint64_t update = masks.free[w] | masks.hit[w];
        if (update == 0) continue;
        // The rule OccupancyMap::publish applies, word by word (publish_word.h).
        view.known[w] |= detail::publishWord(view.log_odds.data() + w * 64, view.known[w], update, masks.hit[w], model);
      }
    }
    for (const EndpointColor& c : updates.colors) {
      const auto it = slot_of.find(detail::packIndex(blockOf(c.ijk)));
      if (it == slot_of.end()) continue;
      auto [entry, inserted] = rebuilt[it->second].colors.try_emplace(offsetInBlock(c.ijk), c.rgb, 1);
      if (inserted) continue;
      // OccupancyMap::publish's running mean, saturating at 127 batches.
      auto& [mean, count] = entry->second;
      for (int k = 0; k < 3; ++k)
        mean[k] = static_cast<uint8_t>((mean[k] * count + c.rgb[k] + (count + 1) / 2) / (count + 1));
      count = std::min(count + 1, 127);
    }
  }

  // 4. Swap them in.
  std::vector<BlockState> states(keys.size());
  for (size_t i = 0; i < keys.size(); ++i) {
    states[i].block = detail::unpackIndex(keys[i]);
    states[i].view = rebuilt[i].view;
    for (const auto& [offset, mean_count] : rebuilt[i].colors) {
      states[i].colors.push_back(
          VoxelColor{static_cast<uint16_t>(offset), mean_count.first, static_cast<uint8_t>(mean_count.second)});
    }
    std::sort(states[i].colors.begin(), states[i].colors.end(),
              [](const VoxelColor& a, const VoxelColor& b) { return a.offset < b.offset; });
  }
  summary.blocks_rebuilt = states.size();
  summary.delta = map_.replaceBlocks(states);
  return summary;
}

}  // namespace cenote::mapping
