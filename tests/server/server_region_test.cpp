// End-to-end: regions of the map on a real server (Admin.ClearBox, ClearSphere, Crop, the region
// of Updates.Subscribe) with finite but huge coordinates. They once went through an int conversion
// that wrapped (a box from 0 to 1e30 cleared nothing and answered OK); now a region is clipped to
// the map's range (mapping/map_range.h), so it acts on exactly the voxels within it: checked against
// brute force over every voxel known before. Bad regions get INVALID_ARGUMENT naming the field.
#include <gtest/gtest.h>

#include <filesystem>
#include <set>

#include "cenote/v1/updates.grpc.pb.h"
#include "tests/clients/cpp/server_process.h"
#include "tests/server/server_test_util.h"

namespace cenote::server::test {
namespace {

namespace fs = std::filesystem;
using client::test::ServerProcess;

struct Known {
  mapping::VoxelIndex ijk;
  mapping::VoxelState state;
};

std::vector<Known> knownVoxels(const mapping::OccupancyMap& map) {
  std::vector<Known> out;
  const auto acc = map.constAccessor();
  for (const mapping::BlockIndex& block : acc.knownBlocks()) {
    for (int o = 0; o < mapping::kBlockVoxels; ++o) {
      const mapping::VoxelIndex ijk = mapping::voxelOfOffset(block, o);
      const mapping::VoxelState state = acc.state(ijk);
      if (state != mapping::VoxelState::kUnknown) out.push_back({ijk, state});
    }
  }
  return out;
}

class ServerRegion : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("cenote-region-" + std::to_string(getpid()));
    fs::create_directories(dir_);
    server_ = std::make_unique<ServerProcess>(CENOTE_SERVER_BINARY);
    stubs_ = std::make_unique<Stubs>(server_->target());
    // Walls on both sides of the origin: known voxels on both sides of every axis plane.
    for (const double x : {2.0, -2.0}) {
      auto context = contextWithDeadline();
      v1::BatchAck ack;
      ASSERT_TRUE(stubs_->ingest->IntegratePoints(context.get(), wallBatch(x, 1.0, 0.05, 1.0), &ack).ok());
    }
    before_ = knownVoxels(*downloadMap(*stubs_->admin, dir_.string()));
    ASSERT_GT(before_.size(), 10000u);
  }
  void TearDown() override { fs::remove_all(dir_); }

  grpc::Status clearBox(const Eigen::Vector3d& min_m, const Eigen::Vector3d& max_m) {
    v1::ClearBoxRequest request;
    setVec(request.mutable_box()->mutable_min(), min_m.x(), min_m.y(), min_m.z());
    setVec(request.mutable_box()->mutable_max(), max_m.x(), max_m.y(), max_m.z());
    auto context = contextWithDeadline();
    v1::ChangeReply reply;
    return stubs_->admin->ClearBox(context.get(), request, &reply);
  }
  template <typename Request>
  Request sphere(const Eigen::Vector3d& c, double radius_m) {
    Request request;
    setVec(request.mutable_centre(), c.x(), c.y(), c.z());
    request.set_radius_m(radius_m);
    return request;
  }
  grpc::Status clearSphere(const Eigen::Vector3d& c, double radius_m) {
    auto context = contextWithDeadline();
    v1::ChangeReply reply;
    return stubs_->admin->ClearSphere(context.get(), sphere<v1::ClearSphereRequest>(c, radius_m), &reply);
  }
  grpc::Status crop(const Eigen::Vector3d& c, double radius_m) {
    auto context = contextWithDeadline();
    v1::ChangeReply reply;
    return stubs_->admin->Crop(context.get(), sphere<v1::CropRequest>(c, radius_m), &reply);
  }

  // Every voxel known before is unknown now where `cleared` holds of its centre, else unchanged.
  // @return the number cleared.
  template <typename Cleared>
  size_t expectCleared(Cleared&& cleared) {
    const auto after = downloadMap(*stubs_->admin, dir_.string());
    const auto acc = after->constAccessor();
    size_t n = 0, wrong = 0;
    for (const Known& v : before_) {
      const bool gone = cleared(after->toPoint(v.ijk));
      n += gone;
      const mapping::VoxelState got = acc.state(v.ijk);
      if (got != (gone ? mapping::VoxelState::kUnknown : v.state) && ++wrong <= 5) {
        ADD_FAILURE() << "voxel (" << v.ijk.transpose() << "): " << (gone ? "not cleared" : "changed");
      }
    }
    EXPECT_EQ(wrong, 0u);
    EXPECT_EQ(knownVoxels(*after).size(), before_.size() - n);
    return n;
  }

  fs::path dir_;
  std::unique_ptr<ServerProcess> server_;
  std::unique_ptr<Stubs> stubs_;
  std::vector<Known> before_;
};

TEST_F(ServerRegion, ClearBoxFromZeroTo1e30ClearsThatHalf) {
  ASSERT_TRUE(clearBox(Eigen::Vector3d(-1e30, 0.0, -1e30), Eigen::Vector3d::Constant(1e30)).ok());
  const size_t cleared = expectCleared([](const Eigen::Vector3d& c) { return c.y() >= 0.0; });
  EXPECT_GT(cleared, before_.size() / 3);
  EXPECT_LT(cleared, before_.size() * 2 / 3);
}

TEST_F(ServerRegion, ClearSphereOfHugeRadiusClearsEverythingWithin) {
  // Far away: nothing within. Centred on x = 1e30 with radius 1e30: everything with x > 0.
  ASSERT_TRUE(clearSphere(Eigen::Vector3d(1e30, 0, 0), 1.0).ok());
  ASSERT_TRUE(clearSphere(Eigen::Vector3d(1e30, 0, 0), 1e30).ok());
  const size_t cleared = expectCleared([](const Eigen::Vector3d& c) { return c.x() > 0.0; });
  EXPECT_GT(cleared, before_.size() / 3);
  ASSERT_TRUE(clearSphere(Eigen::Vector3d::Zero(), 1e300).ok());
  EXPECT_EQ(expectCleared([](const Eigen::Vector3d&) { return true; }), before_.size());
}

TEST_F(ServerRegion, CropToAHugeRadiusKeepsEverythingAndFarAwayNothing) {
  ASSERT_TRUE(crop(Eigen::Vector3d::Zero(), 1e30).ok());
  EXPECT_EQ(expectCleared([](const Eigen::Vector3d&) { return false; }), 0u);
  ASSERT_TRUE(crop(Eigen::Vector3d(1e30, 0, 0), 1e29).ok());
  EXPECT_EQ(expectCleared([](const Eigen::Vector3d&) { return true; }), before_.size());
}

// The snapshot of a subscription whose region runs from y = 0 to 1e30: exactly the known blocks
// holding voxels with y >= 0.
TEST_F(ServerRegion, SubscriptionRegionTo1e30GetsThatHalfsBlocks) {
  auto updates = v1::Updates::NewStub(stubs_->channel);
  v1::SubscribeRequest request;
  setVec(request.mutable_region()->mutable_min(), -1e30, 0.0, -1e30);
  setVec(request.mutable_region()->mutable_max(), 1e30, 1e30, 1e30);
  auto context = contextWithDeadline();
  auto reader = updates->Subscribe(context.get(), request);
  std::set<std::array<int, 3>> got;
  v1::MapUpdate update;
  while (reader->Read(&update)) {
    ASSERT_TRUE(update.snapshot());
    for (const v1::Block& b : update.blocks()) got.insert({b.index().x(), b.index().y(), b.index().z()});
    if (update.snapshot_complete()) break;
  }
  context->TryCancel();
  reader->Finish();
  std::set<std::array<int, 3>> want;
  for (const Known& v : before_) {
    if (v.ijk.y() >= 0) {
      const mapping::BlockIndex b = mapping::blockOf(v.ijk);
      want.insert({b.x(), b.y(), b.z()});
    }
  }
  EXPECT_GT(want.size(), 10u);
  EXPECT_EQ(got, want);
}

TEST_F(ServerRegion, BadRegionsAreInvalidArgumentNamingTheField) {
  grpc::Status s = clearBox(Eigen::Vector3d(0, std::nan(""), 0), Eigen::Vector3d::Ones());
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(s.error_message(), "box.min has a non-finite coordinate");
  s = clearBox(Eigen::Vector3d::Zero(), Eigen::Vector3d(1, HUGE_VAL, 1));
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(s.error_message(), "box.max has a non-finite coordinate");
  s = clearSphere(Eigen::Vector3d::Zero(), -1.0);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(s.error_message(), "radius_m = -1.000000: must be finite and >= 0");
  s = clearSphere(Eigen::Vector3d(HUGE_VAL, 0, 0), 1.0);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(s.error_message(), "centre has a non-finite coordinate");
  s = crop(Eigen::Vector3d::Zero(), HUGE_VAL);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(s.error_message(), "radius_m = inf: must be finite and >= 0");
  auto updates = v1::Updates::NewStub(stubs_->channel);
  v1::SubscribeRequest request;
  setVec(request.mutable_region()->mutable_max(), 1, 1, std::nan(""));
  auto context = contextWithDeadline();
  auto reader = updates->Subscribe(context.get(), request);
  v1::MapUpdate update;
  EXPECT_FALSE(reader->Read(&update));
  s = reader->Finish();
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(s.error_message(), "region.max has a non-finite coordinate");
  expectCleared([](const Eigen::Vector3d&) { return false; });  // none of them changed the map
}

}  // namespace
}  // namespace cenote::server::test
