#include "pipeline/dataset/recording_dataset.h"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "common/error.h"
#include "io/bag/ros_image.h"
#include "io/bag/ros_messages.h"
#include "pipeline/dataset/stamp_pairing.h"

namespace cenote::pipeline {
namespace fs = std::filesystem;
namespace {

constexpr const char* kImage = "sensor_msgs/Image";
constexpr const char* kCompressed = "sensor_msgs/CompressedImage";

bool endsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// <camera namespace>/camera_info: /slave1/image_raw/compressed -> /slave1/camera_info.
std::string infoTopicFor(std::string image_topic) {
  if (endsWith(image_topic, "/compressed")) image_topic.resize(image_topic.size() - 11);
  const size_t slash = image_topic.rfind('/');
  return (slash == std::string::npos ? std::string() : image_topic.substr(0, slash)) + "/camera_info";
}

const io::TopicInfo* findTopic(const io::Recording& rec, const std::string& name) {
  for (const io::TopicInfo& t : rec.topics()) {
    if (t.name == name) return &t;
  }
  return nullptr;
}

// "/a (sensor_msgs/Image, 12 messages), /b (...)" or "none".
std::string imageTopics(const io::Recording& rec) {
  std::string out;
  for (const io::TopicInfo& t : rec.topics()) {
    if (t.type != kImage && t.type != kCompressed) continue;
    out += (out.empty() ? "" : ", ") + t.name + " (" + t.type + ", " + std::to_string(t.message_count) + " messages)";
  }
  return out.empty() ? "none" : out;
}

const io::TopicInfo& imageTopic(const io::Recording& rec, const std::string& name, const std::string& path) {
  const io::TopicInfo* t = findTopic(rec, name);
  if (t == nullptr) throw Error("topic " + name + " is not in " + path + "; its image topics: " + imageTopics(rec));
  if (t->type != kImage && t->type != kCompressed) {
    throw Error("topic " + name + " in " + path + " has type " + t->type + ", not " + kImage + " or " + kCompressed);
  }
  return *t;
}

// The stamp of an image message read in the run's pass, its fields parsed (views of its bytes: no
// pixel is decoded or copied) so that a malformed message fails the pass, where the run reports it.
// Reading the header stamp alone (io::decodeHeaderStampNs) costs the same within measurement
// (docs/PERFORMANCE.md) and would defer that failure to the frame's load().
std::int64_t checkedImageStampNs(const io::RecordedMessage& m) {
  return m.topic->type == kImage ? io::decodeImage(m).stamp_ns : io::decodeCompressedImage(m).stamp_ns;
}

cv::Mat imagePixels(const io::RecordedMessage& m, int image_bits) {
  return m.topic->type == kImage ? io::imageToMat(io::decodeImage(m), m.topic->name, image_bits)
                                 : io::compressedImageToMat(io::decodeCompressedImage(m), m.topic->name);
}

double seconds(std::int64_t ns) { return static_cast<double>(ns) * 1e-9; }  // as EuRoC's ns are read

// One image message, its bytes copied out of the recording's chunk.
struct HeldImage {
  const io::TopicInfo* topic = nullptr;
  std::uint64_t file_offset = 0;
  std::vector<std::uint8_t> bytes;

  io::RecordedMessage view() const {
    io::RecordedMessage m;
    m.topic = topic;
    m.data = bytes;
    m.file_offset = file_offset;
    return m;
  }
};

class RecordingCursor final : public FrameCursor {
 public:
  // `hold_images` false: pairs by stamp without keeping the images' bytes (timestamps only; load()
  // then has nothing to decode).
  RecordingCursor(const std::string& path, const std::string& left, const std::string& right, const RecordingConfig& config,
                  bool hold_images = true)
      : hold_images_(hold_images),
        rec_(io::openRecording(path)),
        left_(findTopic(*rec_, left)),
        wanted_{left, right},
        image_bits_(config.image_bits),
        pairer_(static_cast<std::int64_t>(std::llround(config.sync_tolerance_s * 1e9)),
                static_cast<size_t>(config.sync_queue)) {}

  bool next() override {
    while (true) {
      if (auto pair = pairer_.pop()) {
        current_ = std::move(*pair);
        return true;
      }
      if (ended_) return false;
      io::RecordedMessage m;
      if (!rec_->next(wanted_, m)) {
        pairer_.finish(StereoSide::kLeft);
        pairer_.finish(StereoSide::kRight);
        ended_ = true;
        continue;
      }
      // A timestamps-only pass reads the header stamp alone.
      const std::int64_t stamp = hold_images_ ? checkedImageStampNs(m) : io::decodeHeaderStampNs(m);
      HeldImage image{m.topic, m.file_offset, {}};
      if (hold_images_) image.bytes.assign(m.data.begin(), m.data.end());
      pairer_.push(m.topic == left_ ? StereoSide::kLeft : StereoSide::kRight, stamp, std::move(image));
    }
  }
  double timestamp() const override { return seconds(current_.left.stamp_ns); }
  std::string frameName() const override { return std::to_string(current_.left.stamp_ns); }
  StereoFrame load() override {
    StereoFrame frame;
    frame.t_s = timestamp();
    frame.left = imagePixels(current_.left.value.view(), image_bits_);
    frame.right = imagePixels(current_.right.value.view(), image_bits_);
    return frame;
  }
  std::map<std::string, std::uint64_t> counts() const override {
    return {{"unpaired_images", pairer_.unpaired()},
            {"out_of_order_images", pairer_.outOfOrder()},
            {"damaged_chunks_skipped", rec_->skipped().size()}};
  }
  std::string truncation() const override { return rec_->truncation(); }
  std::vector<std::string> skipped() const override { return rec_->skipped(); }

 private:
  bool hold_images_;
  std::unique_ptr<io::Recording> rec_;
  const io::TopicInfo* left_;
  std::vector<std::string> wanted_;
  int image_bits_;  // RecordingConfig::image_bits
  StampPairer<HeldImage> pairer_;
  StampPairer<HeldImage>::Pair current_;
  bool ended_ = false;
};

}  // namespace

StereoCalibration calibrationFromCameraInfo(const io::RosCameraInfo& left, const io::RosCameraInfo& right,
                                            const std::string& left_topic, const std::string& right_topic) {
  if (left.width != right.width || left.height != right.height) {
    throw Error("CameraInfo on " + left_topic + " is " + std::to_string(left.width) + "x" + std::to_string(left.height) +
                " but on " + right_topic + " " + std::to_string(right.width) + "x" + std::to_string(right.height));
  }
  StereoCalibration c;
  c.image_size = cv::Size(static_cast<int>(left.width), static_cast<int>(left.height));
  const io::RosCameraInfo* infos[2] = {&left, &right};
  const std::string* topics[2] = {&left_topic, &right_topic};
  CameraIntrinsics* out[2] = {&c.left, &c.right};
  cv::Matx33d R_rect_raw[2];
  for (int i = 0; i < 2; ++i) {
    const io::RosCameraInfo& info = *infos[i];
    const std::string& model = info.distortion_model;
    if (!info.D.empty() && model != "plumb_bob" && model != "rational_polynomial") {
      throw Error("CameraInfo on " + *topics[i] + ": distortion model '" + model +
                  "' is not read (plumb_bob or rational_polynomial); give --calibration FILE");
    }
    out[i]->K = cv::Matx33d(info.K.data());
    out[i]->distortion = info.D;
    while (!out[i]->distortion.empty() && out[i]->distortion.size() > 5 && out[i]->distortion.back() == 0.0) {
      out[i]->distortion.pop_back();  // rational_polynomial's 8, OpenCV's 4, 5, 8, 12 or 14
    }
    R_rect_raw[i] = cv::Matx33d(info.R.data());
    if (cv::norm(R_rect_raw[i] * R_rect_raw[i].t() - cv::Matx33d::eye()) > 1e-6) {
      throw Error("CameraInfo on " + *topics[i] + ": R is not a rotation; give --calibration FILE");
    }
  }
  if (right.P[3] == 0.0 || right.P[0] == 0.0) {
    throw Error("CameraInfo on " + right_topic +
                ": P[3] is 0, so it carries no stereo baseline (the right camera's P[3] = -fx' * B); calibrate the pair "
                "as a stereo rig or give --calibration FILE");
  }
  // The rectified right camera is the rectified left one moved by B along x (and -P[7] / fy' along y):
  // p_rect_right = p_rect_left + t, p_rect = R p_raw, so p_right = R_r^T R_l p_left + R_r^T t.
  const cv::Vec3d t(right.P[3] / right.P[0] - (left.P[0] != 0.0 ? left.P[3] / left.P[0] : 0.0),
                    right.P[5] != 0.0 ? right.P[7] / right.P[5] : 0.0, 0.0);
  c.R = R_rect_raw[1].t() * R_rect_raw[0];
  c.T = R_rect_raw[1].t() * t;
  c.validate();
  return c;
}

RecordingDataset::RecordingDataset(const std::string& path, const RecordingTopics& topics, const RecordingConfig& config)
    : path_(path), left_(topics.left), right_(topics.right), config_(config) {
  throwIfInvalid(config.validate(), "bag configuration");
  const std::unique_ptr<io::Recording> rec = io::openRecording(path);
  if (left_.empty() != right_.empty()) throw Error("recording " + path + ": give both --left and --right, or neither");
  if (left_.empty()) {
    std::string tried;
    for (const RigPreset& p : config.rigs) {
      if (config.rig != "auto" && p.name != config.rig) continue;
      if (findTopic(*rec, p.left) != nullptr && findTopic(*rec, p.right) != nullptr) {
        left_ = p.left;
        right_ = p.right;
        break;
      }
      tried += (tried.empty() ? "" : ", ") + p.name + " (" + p.left + ", " + p.right + ")";
    }
    if (left_.empty()) {
      throw Error("recording " + path + ": no --left/--right topics given and it has none of the rig presets' " + tried +
                  "; its image topics: " + imageTopics(*rec));
    }
  }
  if (left_ == right_) throw Error("recording " + path + ": the left and right topics are both " + left_);
  const io::TopicInfo& l = imageTopic(*rec, left_, path);
  const io::TopicInfo& r = imageTopic(*rec, right_, path);
  expected_ = static_cast<size_t>(std::min(l.message_count, r.message_count));
  compression_ = rec->compression();

  if (!topics.calibration.empty()) {
    calibration_ = readCalibrationFile(topics.calibration);
    calibration_source_ = "calibration " + topics.calibration;
    if (fs::path(topics.calibration).filename() == "sensor.yaml") {
      T_body_cam_ = readEurocBodyCamera(topics.calibration);
    }
  } else {
    const std::string li = topics.left_info.empty() ? infoTopicFor(left_) : topics.left_info;
    const std::string ri = topics.right_info.empty() ? infoTopicFor(right_) : topics.right_info;
    for (const std::string* info : {&li, &ri}) {
      const io::TopicInfo* t = findTopic(*rec, *info);
      if (t == nullptr) {
        throw Error("recording " + path + " has no CameraInfo topic " + *info +
                    " for the calibration; give --calibration FILE");
      }
      if (t->type != "sensor_msgs/CameraInfo") {
        throw Error("topic " + *info + " in " + path + " has type " + t->type + ", not sensor_msgs/CameraInfo");
      }
    }
    std::optional<io::RosCameraInfo> left_info, right_info;
    io::RecordedMessage m;
    while ((!left_info || !right_info) && rec->next({li, ri}, m)) {
      (m.topic->name == li ? left_info : right_info) = io::decodeCameraInfo(m);
    }
    if (!left_info || !right_info) throw Error("recording " + path + ": no message on " + (left_info ? ri : li));
    calibration_ = calibrationFromCameraInfo(*left_info, *right_info, li, ri);
    calibration_source_ = "CameraInfo " + li + ", " + ri;
  }
  // The first pair's images must have the calibrated size.
  const std::unique_ptr<FrameCursor> first = frames();
  if (first->next()) {
    const StereoFrame f = first->load();
    for (const auto& [image, topic] : {std::pair{&f.left, &left_}, std::pair{&f.right, &right_}}) {
      if (image->size() != calibration_.image_size) {
        throw Error(calibration_source_ + " is for " + std::to_string(calibration_.image_size.width) + "x" +
                    std::to_string(calibration_.image_size.height) + " images, but those on " + *topic + " are " +
                    std::to_string(image->cols) + "x" + std::to_string(image->rows));
      }
    }
  }
}

double RecordingDataset::timestamp(size_t) const {
  throw FailedPreconditionError("recording " + path_ + " is read front to back (cenote run), not frame by frame");
}
std::string RecordingDataset::frameName(size_t index) const { return std::to_string(timestamp(index)); }
StereoFrame RecordingDataset::load(size_t index) const {
  timestamp(index);
  return {};
}

std::string RecordingDataset::describe() const {
  return "recording " + path_ + ": " + left_ + " + " + right_ + " (" + std::to_string(expected_) + " pairs expected), " +
         calibration_source_ + (compression_.empty() ? "" : "; " + compression_);
}

std::unique_ptr<FrameCursor> RecordingDataset::frames() const {
  return std::make_unique<RecordingCursor>(path_, left_, right_, config_);
}

std::vector<double> RecordingDataset::frameTimes() const {
  RecordingCursor cursor(path_, left_, right_, config_, false);
  std::vector<double> times;
  while (cursor.next()) times.push_back(cursor.timestamp());
  return times;
}

io::Trajectory readPoseTopic(const std::string& path, const std::string& topic, const std::string& parent,
                             const std::string& child, const std::string& image_topic, std::vector<double>* image_times) {
  const std::unique_ptr<io::Recording> rec = io::openRecording(path);
  const io::TopicInfo* t = findTopic(*rec, topic);
  if (t == nullptr) {
    std::string poses;
    for (const io::TopicInfo& x : rec->topics()) {
      if (io::isPoseType(x.type)) poses += (poses.empty() ? "" : ", ") + x.name + " (" + x.type + ")";
    }
    throw Error("pose topic " + topic + " is not in " + path + "; its pose topics: " + (poses.empty() ? "none" : poses));
  }
  if (!io::isPoseType(t->type)) {
    throw Error("pose topic " + topic + " in " + path + " has type " + t->type +
                ", not nav_msgs/Odometry, geometry_msgs/PoseStamped, geometry_msgs/TransformStamped or "
                "tf2_msgs/TFMessage");
  }
  if (t->type == "tf2_msgs/TFMessage" && (parent.empty() || child.empty())) {
    throw Error("pose topic " + topic + " is a tf2_msgs/TFMessage: name the transform with --tf-parent and --tf-child");
  }
  std::vector<io::StampedPose> poses;
  io::RecordedMessage m;
  // Poses at 3/4 or more of the left images are no keyframes (isKeyframeTrajectory's rule): then the
  // images are not read for their stamps. TF republishes stamps, so its message count proves nothing.
  const io::TopicInfo* images = image_topic.empty() ? nullptr : findTopic(*rec, image_topic);
  const bool full_rate = t->type != "tf2_msgs/TFMessage" && images != nullptr && images->message_count > 0 &&
                         4 * t->message_count >= 3 * images->message_count;
  const bool with_images = image_times != nullptr && !image_topic.empty() && image_topic != topic && !full_rate;
  const std::vector<std::string> wanted = with_images ? std::vector<std::string>{topic, image_topic}
                                                      : std::vector<std::string>{topic};
  while (rec->next(wanted, m)) {
    if (with_images && m.topic->name == image_topic) {
      image_times->push_back(seconds(io::decodeHeaderStampNs(m)));  // the stamp only: no pixel copy
      continue;
    }
    const std::optional<io::RosPose> pose = io::decodePose(m, parent, child);
    if (!pose) continue;
    const double t_s = seconds(pose->stamp_ns);
    if (!poses.empty() && t_s <= poses.back().t_s) continue;  // a repeated stamp (TF republishing)
    poses.push_back({t_s, pose->transform()});
  }
  const std::string pair = parent.empty() && child.empty() ? "" : " from " + parent + " to " + child;
  if (poses.empty()) throw Error("pose topic " + topic + " in " + path + " has no poses" + pair);
  return io::Trajectory(std::move(poses), path + ":" + topic);
}

}  // namespace cenote::pipeline
