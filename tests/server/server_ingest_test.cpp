// End-to-end: a real cenote-server on loopback fed a simulated dive over gRPC (poses streamed at
// the ground-truth rate, PNG frames without poses), compared voxel by voxel with `cenote run` on
// the same files; and every kind of bad ingest input rejected with its status code, the map
// unchanged.
#include <gtest/gtest.h>
#include <zlib.h>

#include <sys/resource.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <thread>

#include "common/text_file.h"
#include "mapping/io/map_io.h"
#include "pipeline/dataset/stereo_dataset.h"
#include "pipeline/runner/runner.h"
#include "tests/clients/cpp/server_process.h"
#include "tests/server/server_test_util.h"

namespace cenote::server::test {
namespace {

namespace fs = std::filesystem;
using client::test::ServerProcess;
using client::test::ServerProcessOptions;

void run(const std::string& command) { ASSERT_EQ(std::system(command.c_str()), 0) << command; }

void toWire(const Eigen::Isometry3d& T, v1::Pose* pose) {
  const Eigen::Quaterniond q(T.linear());
  pose->mutable_position()->set_x(T.translation().x());
  pose->mutable_position()->set_y(T.translation().y());
  pose->mutable_position()->set_z(T.translation().z());
  pose->mutable_orientation()->set_x(q.x());
  pose->mutable_orientation()->set_y(q.y());
  pose->mutable_orientation()->set_z(q.z());
  pose->mutable_orientation()->set_w(q.w());
}

// One frame of the dive as the wire carries it: its PNG files, with an identity pose or none.
v1::StereoFrame diveFrame(const std::string& dir, const pipeline::StereoDataset& dataset, size_t i, bool with_pose) {
  v1::StereoFrame frame;
  frame.set_timestamp_s(dataset.timestamp(i));
  const std::string name = dataset.frameName(i) + ".png";
  frame.mutable_left()->set_encoded(readFileBytes((fs::path(dir) / "dive/mav0/cam0/data" / name).string(), "left image"));
  frame.mutable_right()->set_encoded(readFileBytes((fs::path(dir) / "dive/mav0/cam1/data" / name).string(), "right image"));
  if (with_pose) toWire(Eigen::Isometry3d::Identity(), frame.mutable_pose());
  return frame;
}

// Threads of the server at server.ingest_nice (5 in config/default.yaml) steps below the
// server's own nice value, each checked to run on every CPU of this process.
int threadsAtIngestNice(pid_t server) {
  const int ingest_nice = std::min(getpriority(PRIO_PROCESS, static_cast<id_t>(server)) + 5, 19);
  int count = 0;
  for (const ThreadInfo& thread : threadsOf(server)) {
    if (thread.nice != ingest_nice) continue;
    ++count;
    EXPECT_EQ(thread.cpus, cpusOfThisProcess()) << thread.name;
  }
  return count;
}

// A short simulated cave dive and `cenote run`'s map of it, made once for the suite.
class SimulatedDive : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = (fs::temp_directory_path() / ("cenote-server-dive-" + std::to_string(getpid()))).string();
    fs::create_directories(dir_);
    config_ = std::string(CENOTE_SOURCE_DIR) + "/config/default.yaml";
    run(std::string(CENOTE_BINARY) + " sim --scene cave --frames 12 --width 400 --height 300 --quiet --out " + dir_ +
        "/dive > /dev/null");
    run(std::string(CENOTE_BINARY) + " run --dataset " + dir_ + "/dive --config " + config_ + " --out " + dir_ +
        "/run --map " + dir_ + "/run.vdb > /dev/null 2>&1");
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }

  static std::string dir_, config_;
};
std::string SimulatedDive::dir_, SimulatedDive::config_;

TEST_F(SimulatedDive, StreamedFramesAndPosesGiveTheSameMapAsCenoteRun) {
  ServerProcess server(CENOTE_SERVER_BINARY, {.extra_args = {"--config", config_, "--calibration", dir_ + "/dive"}});
  Stubs stubs(server.target());
  const auto dataset = pipeline::openDataset(dir_ + "/dive");
  const io::Trajectory trajectory = pipeline::cameraTrajectory(*dataset, "", "", pipeline::PoseFrame::kAuto);

  {  // Poses first, at the ground-truth rate, as a VIO would send them.
    auto context = contextWithDeadline();
    auto poses = stubs.ingest->StreamPoses(context.get());
    for (const io::StampedPose& p : trajectory.poses()) {
      v1::PoseStamped pose;
      pose.set_timestamp_s(p.t_s);
      toWire(p.T_world_cam, pose.mutable_pose());
      ASSERT_TRUE(poses->Write(pose));
      v1::PoseAck ack;
      ASSERT_TRUE(poses->Read(&ack));
      ASSERT_EQ(ack.status_code(), 0) << ack.message();
    }
    poses->WritesDone();
    ASSERT_TRUE(poses->Finish().ok());
  }
  const int background_before = threadsAtIngestNice(server.pid());
  auto context = contextWithDeadline(300.0);
  auto frames = stubs.ingest->StreamFrames(context.get());
  size_t processed = 0;
  for (size_t i = 0; i < dataset->size(); ++i) {
    ASSERT_TRUE(frames->Write(diveFrame(dir_, *dataset, i, false)));
    v1::FrameAck ack;
    ASSERT_TRUE(frames->Read(&ack));
    EXPECT_EQ(ack.sequence(), i);
    EXPECT_EQ(ack.outcome(), v1::FRAME_OUTCOME_PROCESSED) << ack.message();
    processed += ack.outcome() == v1::FRAME_OUTCOME_PROCESSED;
    if (i == 0) {
      // The stream's stereo, fusion and integrating threads run below the query handlers' CPU
      // priority, on every CPU (they start from a handler thread pinned to the query CPU).
      int background = 0;
      for (int tries = 0; tries < 500 && (background = threadsAtIngestNice(server.pid())) < background_before + 3;
           ++tries) {
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
      }
      EXPECT_GE(background, background_before + 3);
    }
  }
  frames->WritesDone();
  const grpc::Status status = frames->Finish();
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(processed, dataset->size());

  const auto served = downloadMap(*stubs.admin, server.directory());
  const auto offline = mapping::loadMap(dir_ + "/run.vdb");
  const MapDifference diff = compareMaps(*served, *offline);
  std::printf("server vs cenote run: %llu known voxels, %llu with another state, %llu with other log-odds\n",
              static_cast<unsigned long long>(diff.known), static_cast<unsigned long long>(diff.different_state),
              static_cast<unsigned long long>(diff.different_log_odds));
  EXPECT_GT(diff.known, 10000u);
  EXPECT_EQ(diff.different_state, 0u);
  EXPECT_EQ(diff.different_log_odds, 0u);
}

// `frame` with a raw mono8 right image of width x height whose data is `bytes` zeros.
v1::StereoFrame withRawRight(v1::StereoFrame frame, int width, int height, size_t bytes) {
  v1::RawImage* raw = frame.mutable_right()->mutable_raw();
  raw->set_width(width);
  raw->set_height(height);
  raw->set_encoding(v1::IMAGE_ENCODING_MONO8);
  raw->set_data(std::string(bytes, '\0'));
  return frame;
}

TEST_F(SimulatedDive, BadFramesAreRejectedWithTheirStatusAndTheMapIsUnchanged) {
  ServerProcess server(CENOTE_SERVER_BINARY, {.extra_args = {"--config", config_, "--calibration", dir_ + "/dive"}});
  Stubs stubs(server.target());
  const auto dataset = pipeline::openDataset(dir_ + "/dive");
  const v1::StereoFrame good = diveFrame(dir_, *dataset, 0, true);

  std::vector<std::pair<std::string, v1::StereoFrame>> cases;
  v1::StereoFrame corrupt = good;
  corrupt.mutable_left()->set_encoded(good.left().encoded().substr(0, 100));  // a truncated PNG
  cases.push_back({"left", corrupt});
  v1::StereoFrame nan_pose = good;
  nan_pose.mutable_pose()->mutable_position()->set_y(std::nan(""));
  cases.push_back({"pose.position has a non-finite coordinate", nan_pose});
  v1::StereoFrame bad_rotation = good;
  bad_rotation.mutable_pose()->mutable_orientation()->set_w(2.0);
  cases.push_back({"not a unit quaternion", bad_rotation});
  cases.push_back({"expected 120000", withRawRight(good, 400, 300, 1000)});  // 1000 bytes of 400x300
  cases.push_back({"right image is 20x10 but the calibration is for 400x300", withRawRight(good, 20, 10, 200)});
  v1::StereoFrame no_image = good;
  no_image.clear_right();
  cases.push_back({"right: no image data", no_image});

  auto context = contextWithDeadline();
  auto frames = stubs.ingest->StreamFrames(context.get());
  double t = 1.0;
  for (auto& [expected_message, frame] : cases) {
    frame.set_timestamp_s(t += 0.1);
    ASSERT_TRUE(frames->Write(frame));
    v1::FrameAck ack;
    ASSERT_TRUE(frames->Read(&ack));
    EXPECT_EQ(ack.outcome(), v1::FRAME_OUTCOME_REJECTED) << expected_message;
    EXPECT_EQ(ack.status_code(), grpc::StatusCode::INVALID_ARGUMENT) << expected_message;
    EXPECT_NE(ack.message().find(expected_message), std::string::npos) << ack.message();
    EXPECT_EQ(ack.map_version(), 0u);
  }
  // Out of order: a frame no later than the last good-or-bad frame's time.
  v1::StereoFrame late = good;
  late.set_timestamp_s(0.5);
  ASSERT_TRUE(frames->Write(late));
  v1::FrameAck ack;
  ASSERT_TRUE(frames->Read(&ack));
  EXPECT_EQ(ack.status_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(ack.message().find("time order"), std::string::npos) << ack.message();
  // Without a pose of its own and with no poses streamed: skipped, never guessed.
  v1::StereoFrame unposed = good;
  unposed.clear_pose();
  unposed.set_timestamp_s(t += 0.1);
  ASSERT_TRUE(frames->Write(unposed));
  ASSERT_TRUE(frames->Read(&ack));
  EXPECT_EQ(ack.outcome(), v1::FRAME_OUTCOME_SKIPPED_NO_POSE);
  frames->WritesDone();
  EXPECT_TRUE(frames->Finish().ok());

  const v1::MapInfo info = mapInfo(stubs);
  EXPECT_EQ(info.map_version(), 0u);
  EXPECT_EQ(info.occupied() + info.free(), 0u);

  // Positive control: the unchanged frame is processed, so the rejections above came from what
  // each case broke, not from a stream that refuses every frame.
  auto good_context = contextWithDeadline();
  auto good_frames = stubs.ingest->StreamFrames(good_context.get());
  v1::StereoFrame again = good;
  again.set_timestamp_s(t += 0.1);
  ASSERT_TRUE(good_frames->Write(again));
  ASSERT_TRUE(good_frames->Read(&ack));
  EXPECT_EQ(ack.outcome(), v1::FRAME_OUTCOME_PROCESSED) << ack.message();
  good_frames->WritesDone();
  EXPECT_TRUE(good_frames->Finish().ok());
}

// Frames streamed in one call, each with the outcome its ack must have; the map they give.
std::unique_ptr<mapping::OccupancyMap> streamAndDownload(Stubs& stubs, const std::string& dir,
                                                         const std::vector<v1::StereoFrame>& frames,
                                                         const std::vector<v1::FrameOutcome>& outcomes,
                                                         std::vector<v1::FrameAck>* acks) {
  auto reset_context = contextWithDeadline();
  v1::ChangeReply reset;
  EXPECT_TRUE(stubs.admin->Reset(reset_context.get(), v1::ResetRequest(), &reset).ok());
  auto context = contextWithDeadline();
  auto stream = stubs.ingest->StreamFrames(context.get());
  for (size_t i = 0; i < frames.size(); ++i) {
    EXPECT_TRUE(stream->Write(frames[i]));
    v1::FrameAck ack;
    EXPECT_TRUE(stream->Read(&ack));
    EXPECT_EQ(ack.outcome(), outcomes[i]) << "frame " << i << ": " << ack.message();
    if (acks) acks->push_back(ack);
  }
  stream->WritesDone();
  const grpc::Status status = stream->Finish();
  EXPECT_TRUE(status.ok()) << status.error_message();
  return downloadMap(*stubs.admin, dir);
}

// A server on the dive's calibration and `config` without its fusion window: the stereo points of
// each frame go straight into the map, so that two frames map.
// @throws std::runtime_error when `config` has no "fuse: true" to turn off.
ServerProcess serverWithoutFusion(const std::string& config, const std::string& dir) {
  std::string yaml = readFileBytes(config, "config");
  const size_t fuse = yaml.find("  fuse: true");
  if (fuse == std::string::npos) throw std::runtime_error(config + " has no \"  fuse: true\" to turn off");
  yaml.replace(fuse, 12, "  fuse: false");
  const std::string path = dir + "/no_fusion.yaml";
  std::ofstream(path) << yaml;
  return ServerProcess(CENOTE_SERVER_BINARY,
                       ServerProcessOptions{.extra_args = {"--config", path, "--calibration", dir + "/dive"}});
}

TEST_F(SimulatedDive, BadFrameBetweenGoodOnesIsRejectedAloneAndTheGoodOnesAreMapped) {
  const ServerProcess server = serverWithoutFusion(config_, dir_);
  Stubs stubs(server.target());
  const auto dataset = pipeline::openDataset(dir_ + "/dive");
  const v1::StereoFrame first = diveFrame(dir_, *dataset, 0, true), third = diveFrame(dir_, *dataset, 2, true);
  // The second frame's left image as a JPEG cut halfway: OpenCV would decode it padded with grey.
  v1::StereoFrame second = diveFrame(dir_, *dataset, 1, true);
  const std::string& png = second.left().encoded();
  std::vector<uint8_t> jpg;
  ASSERT_TRUE(cv::imencode(".jpg", cv::imdecode(std::vector<uint8_t>(png.begin(), png.end()), cv::IMREAD_UNCHANGED), jpg));
  second.mutable_left()->set_encoded(std::string(jpg.begin(), jpg.begin() + static_cast<long>(jpg.size() / 2)));

  using O = v1::FrameOutcome;
  std::vector<v1::FrameAck> acks;
  const auto mixed = streamAndDownload(stubs, dir_, {first, second, third},
                                       {O::FRAME_OUTCOME_PROCESSED, O::FRAME_OUTCOME_REJECTED, O::FRAME_OUTCOME_PROCESSED},
                                       &acks);
  ASSERT_EQ(acks.size(), 3u);
  EXPECT_EQ(acks[1].message(), "left: JPEG cannot be decoded: Premature end of JPEG file");
  const auto good = streamAndDownload(stubs, dir_, {first, third}, {O::FRAME_OUTCOME_PROCESSED, O::FRAME_OUTCOME_PROCESSED},
                                      nullptr);
  const auto alone = streamAndDownload(stubs, dir_, {first}, {O::FRAME_OUTCOME_PROCESSED}, nullptr);
  const MapDifference diff = compareMaps(*mixed, *good);
  EXPECT_GT(diff.known, 1000u);
  EXPECT_EQ(diff.different_state, 0u);
  EXPECT_EQ(diff.different_log_odds, 0u);
  // Both good frames are in it: the third adds voxels to the first's.
  EXPECT_GT(diff.known, compareMaps(*alone, *alone).known);
}

TEST(ServerWithoutCalibration, StreamFramesFailsWithFailedPrecondition) {
  ServerProcess server(CENOTE_SERVER_BINARY);
  Stubs stubs(server.target());
  auto context = contextWithDeadline();
  auto frames = stubs.ingest->StreamFrames(context.get());
  frames->WritesDone();
  const grpc::Status status = frames->Finish();
  EXPECT_EQ(status.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_NE(status.error_message().find("--calibration"), std::string::npos) << status.error_message();
}

// The batch with its points in xyz_f32 instead of xyz.
v1::PointBatch asFloat32(v1::PointBatch batch) {
  for (double v : batch.xyz()) batch.add_xyz_f32(static_cast<float>(v));
  batch.clear_xyz();
  return batch;
}

TEST(ServerPointIngest, Float32PointsGiveTheSameMapAsDoubles) {
  ServerProcess server(CENOTE_SERVER_BINARY);
  Stubs stubs(server.target());
  const std::string dir = (fs::temp_directory_path() / ("cenote-f32-" + std::to_string(getpid()))).string();
  fs::create_directories(dir);
  // Off-grid coordinates, so that rounding to float32 matters.
  std::vector<v1::PointBatch> batches = {wallBatch(2.0137, 1.0, 0.0231, 1.0), wallBatch(3.0071, 1.5, 0.0297, 2.0)};
  std::unique_ptr<mapping::OccupancyMap> maps[2];
  for (int f32 = 0; f32 < 2; ++f32) {
    auto reset_context = contextWithDeadline();
    v1::ChangeReply reset;
    ASSERT_TRUE(stubs.admin->Reset(reset_context.get(), v1::ResetRequest(), &reset).ok());
    for (const v1::PointBatch& batch : batches) {
      auto context = contextWithDeadline();
      v1::BatchAck ack;
      const grpc::Status status = stubs.ingest->IntegratePoints(context.get(), f32 ? asFloat32(batch) : batch, &ack);
      ASSERT_TRUE(status.ok()) << status.error_message();
    }
    maps[f32] = downloadMap(*stubs.admin, dir);
  }
  const MapDifference diff = compareMaps(*maps[0], *maps[1]);
  EXPECT_GT(diff.known, 50000u);
  EXPECT_EQ(diff.different_state, 0u);
  EXPECT_EQ(diff.different_log_odds, 0u);
  fs::remove_all(dir);
}

TEST(ServerPointIngest, OversizedAndBrokenBatchesAreRefusedAndTheMapIsUnchanged) {
  const std::string config = (fs::temp_directory_path() / ("cenote-limits-" + std::to_string(getpid()) + ".yaml")).string();
  std::ofstream(config) << "server:\n  limits:\n    max_points_per_batch: 1000\n";
  ServerProcess server(CENOTE_SERVER_BINARY, {.extra_args = {"--config", config}});
  Stubs stubs(server.target());

  auto call = [&](const v1::PointBatch& batch) {
    auto context = contextWithDeadline();
    v1::BatchAck ack;
    return stubs.ingest->IntegratePoints(context.get(), batch, &ack);
  };
  const v1::PointBatch big = wallBatch(2.0, 1.0, 0.02, 1.0);  // 101 x 101 points
  grpc::Status status = call(big);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_NE(status.error_message().find("server.limits.max_points_per_batch = 1000"), std::string::npos)
      << status.error_message();

  v1::PointBatch nan_point = wallBatch(2.0, 0.2, 0.05, 1.0);
  nan_point.set_xyz(7, std::nan(""));
  status = call(nan_point);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("point 2 has a non-finite coordinate"), std::string::npos)
      << status.error_message();

  v1::PointBatch ragged = wallBatch(2.0, 0.2, 0.05, 1.0);
  ragged.add_xyz(1.0);
  EXPECT_EQ(call(ragged).error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  v1::PointBatch both = wallBatch(2.0, 0.2, 0.05, 1.0);
  both.add_xyz_f32(1.0f);
  status = call(both);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("xyz and xyz_f32 are both set"), std::string::npos) << status.error_message();
  v1::PointBatch ragged_f32 = asFloat32(wallBatch(2.0, 0.2, 0.05, 1.0));
  ragged_f32.add_xyz_f32(1.0f);
  status = call(ragged_f32);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("xyz_f32: "), std::string::npos) << status.error_message();
  v1::PointBatch bad_colours = wallBatch(2.0, 0.2, 0.05, 1.0);
  bad_colours.set_rgb("abc");
  EXPECT_EQ(call(bad_colours).error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  v1::PointBatch nan_origin = wallBatch(2.0, 0.2, 0.05, 1.0);
  nan_origin.mutable_origin()->set_z(INFINITY);
  EXPECT_EQ(call(nan_origin).error_code(), grpc::StatusCode::INVALID_ARGUMENT);

  v1::MapInfo info = mapInfo(stubs);
  EXPECT_EQ(info.map_version(), 0u);
  EXPECT_EQ(info.occupied() + info.free(), 0u);

  // A pose stream: the NaN pose is rejected in its ack, the good ones around it are stored.
  auto context = contextWithDeadline();
  auto poses = stubs.ingest->StreamPoses(context.get());
  for (int i = 0; i < 3; ++i) {
    v1::PoseStamped pose;
    pose.set_timestamp_s(i);
    toWire(Eigen::Isometry3d::Identity(), pose.mutable_pose());
    if (i == 1) pose.mutable_pose()->mutable_orientation()->set_x(std::nan(""));
    ASSERT_TRUE(poses->Write(pose));
    v1::PoseAck ack;
    ASSERT_TRUE(poses->Read(&ack));
    EXPECT_EQ(ack.status_code(), i == 1 ? grpc::StatusCode::INVALID_ARGUMENT : grpc::StatusCode::OK) << ack.message();
  }
  poses->WritesDone();
  EXPECT_TRUE(poses->Finish().ok());

  // Positive control: a good batch of the same shape goes into the same map, so the map stayed
  // empty above because the batches were refused, not because nothing ever reaches it.
  ASSERT_TRUE(call(wallBatch(2.0, 0.2, 0.05, 1.0)).ok());
  info = mapInfo(stubs);
  EXPECT_GT(info.map_version(), 0u);
  EXPECT_GT(info.occupied(), 0u);
  fs::remove(config);
}

// `png` with byte `offset` of the body of its chunk at `chunk` set to `value` and the chunk's CRC
// recomputed: a well-formed chunk that says something else.
std::string withChunkByte(std::string png, size_t chunk, size_t offset, uint8_t value) {
  const auto* bytes = reinterpret_cast<const uint8_t*>(png.data());
  const uint32_t length = (uint32_t{bytes[chunk]} << 24) | (bytes[chunk + 1] << 16) | (bytes[chunk + 2] << 8) |
                          bytes[chunk + 3];
  png[chunk + 8 + offset] = static_cast<char>(value);
  const uint32_t crc = static_cast<uint32_t>(crc32(0, bytes + chunk + 4, length + 4));
  for (int i = 0; i < 4; ++i) png[chunk + 8 + length + i] = static_cast<char>(crc >> (24 - 8 * i));
  return png;
}

std::string encoded(const std::string& ext, const cv::Mat& image) {
  std::vector<uint8_t> bytes;
  EXPECT_TRUE(cv::imencode(ext, image, bytes)) << ext;
  return std::string(bytes.begin(), bytes.end());
}

TEST_F(SimulatedDive, EveryKindOfBadFrameBetweenGoodOnesIsRejectedAloneWithItsStatus) {
  const ServerProcess server = serverWithoutFusion(config_, dir_);
  Stubs stubs(server.target());
  const auto dataset = pipeline::openDataset(dir_ + "/dive");
  const v1::StereoFrame first = diveFrame(dir_, *dataset, 0, true), second = diveFrame(dir_, *dataset, 1, true),
                        third = diveFrame(dir_, *dataset, 2, true);
  const std::string& left_png = second.left().encoded();
  const cv::Mat left = cv::imdecode(std::vector<uint8_t>(left_png.begin(), left_png.end()), cv::IMREAD_UNCHANGED);
  // OpenCV's PNG writer puts IDAT right after IHDR (the signature's 8 bytes and IHDR's 25).
  const std::string png = encoded(".png", left);
  ASSERT_EQ(png.substr(33 + 4, 4), "IDAT");
  std::string early_end = encoded(".jpg", left);
  early_end[early_end.size() / 2] = static_cast<char>(0xFF);  // an end-of-image marker inside the scan
  early_end[early_end.size() / 2 + 1] = static_cast<char>(0xD9);
  cv::Mat wide, small;
  left.convertTo(wide, CV_16U, 256.0);
  cv::resize(left, small, cv::Size(left.cols / 2, left.rows / 2));
  const auto withLeft = [&](const std::string& bytes) {
    v1::StereoFrame frame = second;
    frame.mutable_left()->set_encoded(bytes);
    return frame;
  };
  v1::StereoFrame odd_channels = second;  // BGR8 announced, one byte per pixel sent
  v1::RawImage* raw = odd_channels.mutable_right()->mutable_raw();
  raw->set_width(left.cols);
  raw->set_height(left.rows);
  raw->set_encoding(v1::IMAGE_ENCODING_BGR8);
  raw->set_data(std::string(left.total(), '\0'));

  const std::vector<std::pair<v1::StereoFrame, std::string>> kinds = {
      // Past every header check, failing inside the decoders (libpng through OpenCV, libjpeg).
      {withLeft(withChunkByte(png, 33, 0, 0x00)), "left: PNG cannot be decoded: its compressed image data is damaged"},
      {withLeft(early_end), "left: JPEG cannot be decoded: Corrupt JPEG data: premature end of data segment"},
      // Refused from the header or the raw image's description, before decoding.
      {withLeft(encoded(".png", wide)), "left: PNG has 16-bit samples; frames must be 8-bit"},
      {withLeft(withChunkByte(png, 8, 9, 4)), "left: PNG is grey with alpha (2 channels); frames are grey, BGR or BGRA"},
      {withLeft(encoded(".png", small)), "left image is 200x150 but the calibration is for 400x300"},
      {odd_channels, "right: raw image has 120000 bytes, expected 360000 for 400x300x3"},
  };
  using O = v1::FrameOutcome;
  const auto good = streamAndDownload(stubs, dir_, {first, third}, {O::FRAME_OUTCOME_PROCESSED, O::FRAME_OUTCOME_PROCESSED},
                                      nullptr);
  for (const auto& [bad, message] : kinds) {
    std::vector<v1::FrameAck> acks;
    const auto mixed = streamAndDownload(
        stubs, dir_, {first, bad, third},
        {O::FRAME_OUTCOME_PROCESSED, O::FRAME_OUTCOME_REJECTED, O::FRAME_OUTCOME_PROCESSED}, &acks);
    ASSERT_EQ(acks.size(), 3u) << message;
    EXPECT_EQ(acks[1].status_code(), grpc::StatusCode::INVALID_ARGUMENT) << message;
    EXPECT_EQ(acks[1].message(), message);
    EXPECT_EQ(acks[2].sequence(), 2u) << message;
    const MapDifference diff = compareMaps(*mixed, *good);
    EXPECT_GT(diff.known, 1000u) << message;
    EXPECT_EQ(diff.different_state, 0u) << message;
    EXPECT_EQ(diff.different_log_odds, 0u) << message;
  }
}

}  // namespace
}  // namespace cenote::server::test
