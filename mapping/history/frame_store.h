// frame_store.h: the disk-backed store of integrated frames behind pose corrections: two files per
// frame in a folder, its two encoded sections (frame_codec.h: SEQ.points, SEQ.updates), so that a
// moved frame rewrites its updates alone (a tenth of its bytes), and a third for a frame whose
// updates were resampled rather than marched (SEQ.marched: the updates of its last ray march, which
// every later resampling starts from, frame_resample.h); in memory only each frame's time, poses
// and section sizes. Bounded: overBudget() names the oldest frames to drop once the files pass the
// budget (the caller, MapHistory, drops them with erase()).
// Units: bytes, seconds, metres. Threads: one owner writes; the const reads (contains, meta,
// readPoints, readUpdates, readMarched: each opens its file and preads) may run on several threads
// at once while nothing writes.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace cenote::mapping::history {

struct FrameMeta {
  double t_s = 0.0;
  bool correctable = false;                                       // integrated with a camera pose: corrections may move it
  Eigen::Isometry3d T_world_cam = Eigen::Isometry3d::Identity();  // the pose it is integrated with now
  Eigen::Isometry3d T_world_cam_marched = Eigen::Isometry3d::Identity();  // the pose of its marched updates
  Eigen::Isometry3d T_pose_cam = Eigen::Isometry3d::Identity();           // the camera in the corrections' pose frame
  Eigen::Vector3d origin_cam = Eigen::Vector3d::Zero();                   // the batch's ray origin, camera frame
};

class FrameStore {
 public:
  // `dir` empty: a new folder under the system's temp folder, removed with the store; otherwise
  // `dir` is created when missing and the store's files in it are removed with the store.
  // @throws IoError when the folder cannot be made.
  FrameStore(const std::string& dir, uint64_t max_bytes);
  ~FrameStore();
  FrameStore(const FrameStore&) = delete;
  FrameStore& operator=(const FrameStore&) = delete;

  // Writes frame `seq`, new to the store. @throws ResourceExhaustedError (disk full) or IoError,
  // the frame then not in the store; Error when it already is.
  void put(uint32_t seq, const FrameMeta& meta, const std::string& points, const std::string& updates);
  // Rewrites the metadata and the updates of stored frame `seq` (a moved frame: its points stay),
  // updates marched again: they are the frame's marched updates from now on.
  // @throws NotFoundError for a frame not in the store; ResourceExhaustedError or IoError, leaving
  // the frame as it was.
  void putUpdates(uint32_t seq, const FrameMeta& meta, const std::string& updates);
  // The same for updates resampled from readMarched(seq), which stay as they are.
  // @throws as putUpdates.
  void putResampled(uint32_t seq, const FrameMeta& meta, const std::string& updates);
  // @throws IoError when the file cannot be read; NotFoundError for a frame not in the store.
  std::string readPoints(uint32_t seq) const;
  std::string readUpdates(uint32_t seq) const;  // the updates it is integrated with now
  std::string readMarched(uint32_t seq) const;  // those of its last ray march (at meta.T_world_cam_marched)
  // Whether the frame's updates are resampled (putResampled), not those of its last march.
  bool isResampled(uint32_t seq) const { return entryOf(seq).marched_bytes != 0; }
  void erase(uint32_t seq);
  void clear();

  const FrameMeta& meta(uint32_t seq) const;
  bool contains(uint32_t seq) const { return frames_.count(seq) != 0; }
  // The oldest frames whose removal brings the files within the budget (none while within it).
  std::vector<uint32_t> overBudget() const;
  // Frames in ascending seq, with their metadata.
  template <typename Visit>
  void forEach(Visit&& visit) const {
    for (const auto& [seq, entry] : frames_) visit(seq, entry.meta);
  }
  size_t numFrames() const { return frames_.size(); }
  uint64_t bytes() const { return bytes_; }
  uint64_t maxBytes() const { return max_bytes_; }
  const std::string& dir() const { return dir_; }

 private:
  struct Entry {
    FrameMeta meta;
    uint64_t points_bytes = 0;
    uint64_t updates_bytes = 0;
    uint64_t marched_bytes = 0;  // 0: the updates are the marched ones (no SEQ.marched)
  };
  std::string pathOf(uint32_t seq, const char* section) const;
  const Entry& entryOf(uint32_t seq) const;
  std::string readSection(uint32_t seq, const char* section, uint64_t size) const;
  void unlinkAll(uint32_t seq, const Entry& entry) const;

  std::string dir_;
  bool own_dir_ = false;
  uint64_t max_bytes_;
  uint64_t bytes_ = 0;
  std::map<uint32_t, Entry> frames_;
};

}  // namespace cenote::mapping::history
