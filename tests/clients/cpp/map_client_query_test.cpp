// map_client_query_test.cpp: every query of cenote-server, called through the C++ client on a real
// server process, against known answers: the analytic wall scene (wall_scene.h) and the same
// queries run in-process on a mapping::OccupancyMap that integrated the same batch. Also the
// bearer token (missing / wrong -> UNAUTHENTICATED, map unchanged) and bad requests (oversized ->
// RESOURCE_EXHAUSTED, NaN -> INVALID_ARGUMENT, map unchanged).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>
#include <random>

#include "clients/cpp/map_client.h"
#include "mapping/distance/distance_field.h"
#include "mapping/frontier/frontier_map.h"
#include "mapping/query/map_query.h"
#include "tests/clients/cpp/server_process.h"
#include "tests/clients/cpp/wall_scene.h"

namespace cenote::client::test {
namespace {

constexpr const char* kToken = "e2e-secret-token";

class MapClientQueryTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    ServerProcessOptions options;
    options.token = kToken;
    server_ = new ServerProcess(CENOTE_SERVER_BINARY, options);
    MapClient client(server_->target(), authorized());
    const BatchAck ack = client.integratePoints(wallBatch());
    ASSERT_TRUE(ack.ok()) << ack.message;
    // The reference: the same batch on an in-process map with the server's default settings.
    reference_ = new mapping::OccupancyMap(mapping::MapConfig{});
    const mapping::MapDelta delta = reference_->integrate(toMappingBatch(wallBatch()));
    distance_ = new mapping::DistanceField(*reference_);
    distance_->update(delta);
    frontiers_ = new mapping::FrontierMap(*reference_);
    frontiers_->update(delta);
  }
  static void TearDownTestSuite() {
    delete frontiers_;
    delete distance_;
    delete reference_;
    if (server_) {
      EXPECT_EQ(server_->stop(), 0) << "cenote-server should exit 0 on SIGTERM: " << server_->log();
    }
    delete server_;
  }
  void SetUp() override { ASSERT_NE(server_, nullptr); }

  static ClientOptions authorized() {
    ClientOptions options;
    options.token = kToken;
    return options;
  }
  static MapClient client(const ClientOptions& options = authorized()) { return MapClient(server_->target(), options); }

  // The map's version and counts: what "unchanged" compares.
  static std::tuple<uint64_t, uint64_t, uint64_t> fingerprint() {
    const MapInfo info = client().info();
    return {info.map_version, info.occupied, info.free};
  }

  static ServerProcess* server_;
  static mapping::OccupancyMap* reference_;
  static mapping::DistanceField* distance_;
  static mapping::FrontierMap* frontiers_;
};

ServerProcess* MapClientQueryTest::server_ = nullptr;
mapping::OccupancyMap* MapClientQueryTest::reference_ = nullptr;
mapping::DistanceField* MapClientQueryTest::distance_ = nullptr;
mapping::FrontierMap* MapClientQueryTest::frontiers_ = nullptr;

// Points scattered over the observed region and around it (fixed seed).
std::vector<Eigen::Vector3d> scatteredPoints(size_t n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> x(-0.5, 2.6), yz(-1.3, 1.3);
  std::vector<Eigen::Vector3d> points(n);
  for (auto& p : points) p = Eigen::Vector3d(x(rng), yz(rng), yz(rng));
  return points;
}

mapping::Aabb toAabb(const Box& box) {
  mapping::Aabb out;
  out.min_m = box.min_m;
  out.max_m = box.max_m;
  return out;
}

TEST_F(MapClientQueryTest, VoxelStatesOfTheWallSceneAreKnownExactly) {
  MapClient map = client();
  const std::vector<Eigen::Vector3d> points = {centre(kWallX, 0, 0),                // on the wall
                                               centre(kWallX, kWallMin, kWallMax),  // the wall's corner
                                               centre(20, 0, 0),                    // half way along the central ray
                                               centre(kWallX + 1, 0, 0),            // just behind the wall
                                               centre(-1, 0, 0),                    // behind the camera
                                               Eigen::Vector3d(50, 50, 50)};        // far away
  const auto results = map.voxels(points);
  ASSERT_EQ(results.size(), points.size());
  EXPECT_EQ(results[0].state, VoxelState::kOccupied);
  EXPECT_NEAR(results[0].probability, 0.7, 1e-6);  // one hit from unknown: prob_hit
  EXPECT_EQ(results[1].state, VoxelState::kOccupied);
  EXPECT_EQ(results[2].state, VoxelState::kFree);
  EXPECT_NEAR(results[2].probability, 0.4, 1e-6);  // one miss from unknown: prob_miss
  for (size_t i = 3; i < points.size(); ++i) {
    EXPECT_EQ(results[i].state, VoxelState::kUnknown) << "point " << i;
    EXPECT_EQ(results[i].probability, 0.5f) << "point " << i;
  }
}

TEST_F(MapClientQueryTest, VoxelStatesEqualTheInProcessMapAlsoWhenSplitIntoBatches) {
  const auto points = scatteredPoints(5000, 7);
  const auto expected = mapping::queryVoxels(*reference_, points);
  ClientOptions small_batches = authorized();
  small_batches.max_batch_items = 700;  // 8 requests, the last one short
  for (const ClientOptions& options : {authorized(), small_batches}) {
    const auto results = client(options).voxels(points);
    ASSERT_EQ(results.size(), points.size());
    int mismatches = 0;
    for (size_t i = 0; i < points.size(); ++i) {
      const bool same = static_cast<int>(results[i].state) == static_cast<int>(expected[i].state) &&
                        std::abs(results[i].probability - expected[i].probability) < 1e-6;
      if (!same && ++mismatches <= 5) {
        ADD_FAILURE() << "point " << points[i].transpose() << ": server " << toString(results[i].state) << " "
                      << results[i].probability << ", in-process " << mapping::toString(expected[i].state) << " "
                      << expected[i].probability;
      }
    }
    EXPECT_EQ(mismatches, 0);
  }
}

TEST_F(MapClientQueryTest, BoxCountsAreAnalyticAndEqualTheInProcessMap) {
  MapClient map = client();
  const double s = kVoxel_m;
  const Box wall{{2.0 + 0.2 * s, -1.0, -1.0}, {2.05 - 0.2 * s, 1.0, 1.0}};  // the wall's voxel centres
  const Box behind{{2.06, -0.24, -0.24}, {2.54, 0.24, 0.24}};               // 10 x 10 x 10 centres
  std::vector<Box> boxes = {wall, behind};
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> corner(-0.6, 2.4), size(0.0, 0.8);
  for (int i = 0; i < 50; ++i) {
    const Eigen::Vector3d lo(corner(rng), corner(rng) - 0.9, corner(rng) - 0.9);
    boxes.push_back({lo, lo + Eigen::Vector3d(size(rng), size(rng), size(rng))});
  }
  const auto counts = map.boxes(boxes);
  ASSERT_EQ(counts.size(), boxes.size());
  EXPECT_EQ(counts[0].occupied, 1600u);
  EXPECT_EQ(counts[0].free, 0u);
  EXPECT_EQ(counts[0].unknown, 0u);
  EXPECT_TRUE(counts[0].any_occupied);
  EXPECT_EQ(counts[1].unknown, 1000u);
  EXPECT_EQ(counts[1].total(), 1000u);
  EXPECT_FALSE(counts[1].any_occupied);
  std::vector<mapping::Aabb> aabbs;
  for (const Box& b : boxes) aabbs.push_back(toAabb(b));
  const auto expected = mapping::queryBoxes(*reference_, aabbs);
  for (size_t i = 0; i < boxes.size(); ++i) {
    EXPECT_EQ(counts[i].occupied, expected[i].occupied) << "box " << i;
    EXPECT_EQ(counts[i].free, expected[i].free) << "box " << i;
    EXPECT_EQ(counts[i].unknown, expected[i].unknown) << "box " << i;
  }
}

void expectSameCollision(const Collision& got, const mapping::CollisionResult& want, const std::string& where) {
  EXPECT_EQ(got.hit, want.hit) << where;
  EXPECT_EQ(got.crossed_unknown, want.crossed_unknown) << where;
  EXPECT_EQ(got.stopped_at_unknown, want.stopped_at_unknown) << where;
  EXPECT_EQ(got.clear, want.isClear()) << where;
  if (want.hit) {
    EXPECT_NEAR(got.hit_distance_m, want.hit_distance_m, 1e-9) << where;
    EXPECT_EQ(got.hit_voxel, want.hit_voxel) << where;
  }
  if (want.crossed_unknown) {
    EXPECT_NEAR(got.unknown_distance_m, want.unknown_distance_m, 1e-9) << where;
  }
}

TEST_F(MapClientQueryTest, SegmentHitsTheWallAtItsKnownDistance) {
  MapClient map = client();
  const Eigen::Vector3d start = centre(10, 0, 0);  // x = 0.525
  const Collision through = map.segment({start, centre(60, 0, 0), 0.0});
  EXPECT_TRUE(through.hit);
  EXPECT_FALSE(through.clear);
  EXPECT_EQ(through.hit_voxel, Eigen::Vector3i(kWallX, 0, 0));
  EXPECT_NEAR(through.hit_distance_m, centre(kWallX) - centre(10), 1e-9);  // 1.5 m
  EXPECT_TRUE(through.hit_point_m.isApprox(centre(kWallX, 0, 0), 1e-9));
  const Collision short_of_wall = map.segment({start, centre(30, 0, 0), 0.0});
  EXPECT_FALSE(short_of_wall.hit);
}

TEST_F(MapClientQueryTest, CapsuleHitsTheWallOnlyWhenItsRadiusReachesIt) {
  MapClient map = client();
  // Parallel to the wall, 0.2 m in front of its voxel centres.
  const Eigen::Vector3d a(centre(kWallX) - 0.2, -0.3, centre(0));
  const Eigen::Vector3d b(centre(kWallX) - 0.2, 0.3, centre(0));
  const auto results = map.segments({{a, b, 0.25}, {a, b, 0.1}});
  EXPECT_TRUE(results[0].hit);
  EXPECT_EQ(results[0].hit_voxel.x(), kWallX);
  EXPECT_FALSE(results[1].hit);
}

TEST_F(MapClientQueryTest, SegmentsAndCapsulesEqualTheInProcessMap) {
  MapClient map = client();
  const auto starts = scatteredPoints(300, 11);
  const auto ends = scatteredPoints(300, 12);
  std::vector<Segment> segments;
  std::vector<mapping::SegmentQuery> queries;
  for (size_t i = 0; i < starts.size(); ++i) {
    const double radius = (i % 3) * 0.05;
    segments.push_back({starts[i], ends[i], radius});
    queries.push_back({starts[i], ends[i], radius});
  }
  for (bool stop_at_unknown : {false, true}) {
    const auto got = map.segments(segments, stop_at_unknown);
    const auto want = mapping::checkSegments(*reference_, queries, stop_at_unknown);
    ASSERT_EQ(got.size(), want.size());
    for (size_t i = 0; i < got.size(); ++i) {
      expectSameCollision(got[i], want[i],
                          "segment " + std::to_string(i) + " stop_at_unknown " + std::to_string(stop_at_unknown));
    }
  }
}

TEST_F(MapClientQueryTest, RaycastHitsTheWallAndSeesUnknownBehindTheCamera) {
  MapClient map = client();
  const auto results = map.raycast({{kOrigin_m, Eigen::Vector3d(2, 0, 0)}, {kOrigin_m, Eigen::Vector3d(-1, 0, 0)}}, 5.0);
  EXPECT_TRUE(results[0].hit);
  EXPECT_EQ(results[0].hit_voxel, Eigen::Vector3i(kWallX, 0, 0));
  EXPECT_NEAR(results[0].hit_distance_m, centre(kWallX) - centre(0), 1e-9);  // 2.0 m
  EXPECT_FALSE(results[1].hit);
  EXPECT_TRUE(results[1].crossed_unknown);
  const auto stopping = map.raycast({{kOrigin_m, Eigen::Vector3d(-1, 0, 0)}}, 5.0, true);
  EXPECT_TRUE(stopping[0].stopped_at_unknown);
  EXPECT_FALSE(stopping[0].clear);
  const auto want = mapping::raycast(
      *reference_, {{kOrigin_m, Eigen::Vector3d(2, 0, 0)}, {kOrigin_m, Eigen::Vector3d(-1, 0, 0)}}, 5.0, false);
  expectSameCollision(results[0], want[0], "ray +x");
  expectSameCollision(results[1], want[1], "ray -x");
}

TEST_F(MapClientQueryTest, DistanceToTheWallIsWithinOneVoxelAndEqualsTheInProcessField) {
  MapClient map = client();
  const MapInfo info = map.info();
  const std::vector<Eigen::Vector3d> points = {Eigen::Vector3d(centre(kWallX) - 0.5, centre(0), centre(0)),
                                               Eigen::Vector3d(centre(kWallX) - 1.0, 0.3, -0.2),
                                               Eigen::Vector3d(-3.0, 0.0, 0.0)};
  const auto results = map.distances(points);
  ASSERT_EQ(results.size(), 3u);
  for (int i = 0; i < 2; ++i) {
    const double want = i == 0 ? 0.5 : 1.0;
    EXPECT_NEAR(results[i].distance_m, want, kVoxel_m) << "point " << i;
    EXPECT_TRUE(results[i].within_max);
    EXPECT_GT(results[i].gradient.dot(Eigen::Vector3d(-1, 0, 0)), 0.95) << "gradient " << results[i].gradient.transpose();
  }
  EXPECT_FALSE(results[2].within_max);
  EXPECT_NEAR(results[2].distance_m, info.max_distance_m, 1e-6);
  EXPECT_EQ(results[2].gradient, Eigen::Vector3d::Zero());

  const auto scattered = scatteredPoints(2000, 5);
  const auto got = map.distances(scattered);
  const auto want = distance_->query(scattered);
  for (size_t i = 0; i < scattered.size(); ++i) {
    ASSERT_NEAR(got[i].distance_m, want[i].distance_m, 1e-5) << "point " << scattered[i].transpose();
    ASSERT_EQ(got[i].within_max, want[i].within_max) << "point " << scattered[i].transpose();
    ASSERT_LT((got[i].gradient - want[i].gradient).norm(), 1e-5) << "point " << scattered[i].transpose();
  }
}

TEST_F(MapClientQueryTest, FrontiersLieOnTheEdgeOfTheObservedRegionAndEqualTheInProcessOnes) {
  MapClient map = client();
  const auto got = map.frontiers({kOrigin_m, Box{}, 0});
  ASSERT_FALSE(got.empty());
  // The observed region: the pyramid from the origin to the wall.
  const Eigen::Vector3d lo(-kVoxel_m, -1.0 - kVoxel_m, -1.0 - kVoxel_m),
      hi(2.05 + kVoxel_m, 1.0 + kVoxel_m, 1.0 + kVoxel_m);
  uint64_t voxels = 0;
  for (const Frontier& f : got) {
    voxels += f.num_voxels;
    EXPECT_TRUE((f.bounds.min_m.array() >= lo.array()).all() && (f.bounds.max_m.array() <= hi.array()).all())
        << "frontier " << f.id << " bounds " << f.bounds.min_m.transpose() << " .. " << f.bounds.max_m.transpose();
    EXPECT_NEAR(f.direction.norm(), 1.0, 1e-3) << "frontier " << f.id;
    EXPECT_NEAR(f.distance_m, (f.centroid_m - kOrigin_m).norm(), 1e-6);
  }
  for (size_t i = 1; i < got.size(); ++i) EXPECT_LE(got[i - 1].distance_m, got[i].distance_m);
  // Every frontier voxel is free; the cluster's voxels next to unknown: the mean direction points
  // into unknown space at one voxel from some of its voxels.
  const auto want = frontiers_->clusters(kOrigin_m);
  ASSERT_EQ(got.size(), want.size());
  uint64_t want_voxels = 0;
  for (size_t i = 0; i < want.size(); ++i) {
    want_voxels += want[i].num_voxels;
    EXPECT_EQ(got[i].num_voxels, want[i].num_voxels) << "cluster " << i;
    EXPECT_LT((got[i].centroid_m - want[i].centroid_m).norm(), 1e-6) << "cluster " << i;
  }
  EXPECT_EQ(voxels, want_voxels);
  EXPECT_EQ(voxels, frontiers_->numFrontierVoxels());

  // max_clusters and the region filter.
  const auto nearest = map.frontiers({kOrigin_m, Box{}, 2});
  ASSERT_EQ(nearest.size(), std::min<size_t>(2, got.size()));
  EXPECT_EQ(nearest[0].num_voxels, got[0].num_voxels);
  const Box far_side{{1.0, -2.0, -2.0}, {3.0, 2.0, 2.0}};
  ASSERT_FALSE(map.frontiers({kOrigin_m, far_side, 0}).empty()) << "premise of the loop: the region has frontiers";
  for (const Frontier& f : map.frontiers({kOrigin_m, far_side, 0})) {
    EXPECT_GE(f.centroid_m.x(), 1.0) << "frontier " << f.id << " outside the region";
  }
}

TEST_F(MapClientQueryTest, ExtractListsTheBoxVoxelsWithTheirStates) {
  MapClient map = client();
  // Centres x in {1.925 .. 2.175} (6), y and z in {-0.075 .. 0.075} (4 each).
  const Box box{{1.9, -0.1, -0.1}, {2.2, 0.1, 0.1}};
  const ExtractedVoxels all = map.extract(box, true);
  EXPECT_NEAR(all.voxel_size_m, kVoxel_m, 1e-12);
  EXPECT_EQ(all.size(), 96u);
  const ExtractedVoxels known = map.extract(box, false);
  size_t occupied = 0;
  auto acc = reference_->constAccessor();
  for (size_t i = 0; i < known.size(); ++i) {
    const Eigen::Vector3i& ijk = known.ijk[i];
    EXPECT_NE(known.states[i], VoxelState::kUnknown);
    EXPECT_EQ(static_cast<int>(known.states[i]), static_cast<int>(acc.state(ijk))) << "voxel " << ijk.transpose();
    EXPECT_NEAR(known.probabilities[i], acc.probability(ijk), 1e-6);
    if (known.states[i] == VoxelState::kOccupied) {
      ++occupied;
      EXPECT_EQ(ijk.x(), kWallX);
    }
  }
  EXPECT_EQ(occupied, 16u);  // the wall's 4 x 4 voxels in the box
  size_t expected_known = 0;
  for (const Eigen::Vector3i& ijk : all.ijk) expected_known += acc.state(ijk) != mapping::VoxelState::kUnknown;
  EXPECT_EQ(known.size(), expected_known);
}

TEST_F(MapClientQueryTest, MapInfoDescribesTheMap) {
  const MapInfo info = client().info();
  const mapping::MapStats stats = reference_->stats();
  EXPECT_NEAR(info.voxel_size_m, kVoxel_m, 1e-12);
  EXPECT_EQ(info.frame_id, "world");
  EXPECT_EQ(info.occupied, 1600u);
  EXPECT_EQ(info.occupied, stats.occupied);
  EXPECT_EQ(info.free, stats.free);
  EXPECT_TRUE(info.bounds.min_m.isApprox(stats.bounds_m.min_m, 1e-9)) << info.bounds.min_m.transpose();
  EXPECT_TRUE(info.bounds.max_m.isApprox(stats.bounds_m.max_m, 1e-9)) << info.bounds.max_m.transpose();
  EXPECT_NEAR(info.prob_hit, 0.7, 1e-12);
  EXPECT_NEAR(info.prob_miss, 0.4, 1e-12);
  EXPECT_NEAR(info.clamp_min, 0.12, 1e-12);
  EXPECT_NEAR(info.clamp_max, 0.97, 1e-12);
  EXPECT_NEAR(info.max_distance_m, 2.0, 1e-12);
  EXPECT_GE(info.map_version, 1u);
}

TEST_F(MapClientQueryTest, MissingOrWrongTokenIsUnauthenticatedAndChangesNothing) {
  const auto before = fingerprint();
  ClientOptions no_token;
  ClientOptions wrong_token;
  wrong_token.token = "not-the-token";
  for (const ClientOptions& options : {no_token, wrong_token}) {
    MapClient map = client(options);
    const std::string who = options.token.empty() ? "no token" : "wrong token";
    try {
      map.voxels({centre(kWallX, 0, 0)});
      ADD_FAILURE() << who << ": query succeeded";
    } catch (const RpcError& e) {
      EXPECT_EQ(e.code(), grpc::StatusCode::UNAUTHENTICATED) << who << ": " << e.what();
      EXPECT_STREQ(e.codeName(), "UNAUTHENTICATED");
    }
    EXPECT_THROW(map.integratePoints(wallBatch(kWallX - 5)), RpcError) << who;
    EXPECT_THROW(map.reset(), RpcError) << who;
    EXPECT_THROW(map.clearBox({{-5, -5, -5}, {5, 5, 5}}), RpcError) << who;
    EXPECT_THROW(map.stats(), RpcError) << who;
  }
  EXPECT_EQ(fingerprint(), before);
}

// `call` is refused with RESOURCE_EXHAUSTED, the message naming the limit's key; `asked` says what
// the call asked for.
template <typename Call>
void expectBeyondLimit(Call&& call, const std::string& limit_key, const std::string& asked) {
  try {
    call();
    ADD_FAILURE() << asked << " succeeded";
  } catch (const RpcError& e) {
    EXPECT_EQ(e.code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << e.what();
    EXPECT_NE(e.message().find(limit_key), std::string::npos) << e.what();
  }
}

TEST_F(MapClientQueryTest, OversizedRequestsAreResourceExhaustedNamingTheLimit) {
  const auto before = fingerprint();
  ClientOptions unsplit = authorized();
  unsplit.max_batch_items = 0;  // send it whole: the server decides
  MapClient map = client(unsplit);
  const std::vector<Eigen::Vector3d> too_many(100001, centre(1, 1, 1));
  expectBeyondLimit([&] { map.voxels(too_many); }, "max_batch", "100001 points in one query");
  // 400^3 voxels > max_box_voxels
  expectBeyondLimit([&] { map.boxes({{{-10, -10, -10}, {10, 10, 10}}}); }, "max_box_voxels", "a 20 m box");
  // A 20 m capsule: about 800^3 voxels.
  expectBeyondLimit([&] { map.segments({{kOrigin_m, centre(5, 0, 0), 20.0}}); }, "max_box_voxels", "a 20 m capsule");
  PointBatch huge;
  huge.origin_m = kOrigin_m;
  huge.points_m.assign(1000001, centre(30, 0, 0));
  expectBeyondLimit([&] { map.integratePoints(huge); }, "max_points_per_batch", "a 1000001-point batch");
  EXPECT_EQ(fingerprint(), before);
}

TEST_F(MapClientQueryTest, NonFiniteOrNegativeInputIsInvalidArgumentAndChangesNothing) {
  const auto before = fingerprint();
  MapClient map = client();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  PointBatch batch = wallBatch(kWallX - 10);
  batch.points_m[17].y() = nan;
  try {
    map.integratePoints(batch);
    ADD_FAILURE() << "a batch with a NaN point was integrated";
  } catch (const RpcError& e) {
    EXPECT_EQ(e.code(), grpc::StatusCode::INVALID_ARGUMENT) << e.what();
  }
  PointBatch bad_origin = wallBatch(kWallX - 10);
  bad_origin.origin_m.z() = std::numeric_limits<double>::infinity();
  EXPECT_THROW(map.integratePoints(bad_origin), RpcError);
  for (const auto& call : std::vector<std::function<void()>>{
           [&] { map.voxels({Eigen::Vector3d(nan, 0, 0)}); },
           [&] {
             map.segments({{kOrigin_m, centre(5, 0, 0), -0.1}});
           },
           [&] { map.clearSphere(kOrigin_m, -1.0); },
           [&] {
             map.raycast({{kOrigin_m, Eigen::Vector3d::Zero()}}, 5.0);
           },
           // Far beyond the map's range (voxel indices would overflow): a clear error, no hang.
           [&] {
             map.segments({{Eigen::Vector3d(-1e12, 0, 0), Eigen::Vector3d(-1e12 + 1, 0, 0), 0.1}});
           },
           [&] {
             map.extract({Eigen::Vector3d(1e12, 0, 0), Eigen::Vector3d(1e12 + 0.1, 0.1, 0.1)});
           }}) {
    try {
      call();
      ADD_FAILURE() << "bad input accepted";
    } catch (const RpcError& e) {
      EXPECT_EQ(e.code(), grpc::StatusCode::INVALID_ARGUMENT) << e.what();
    }
  }
  EXPECT_EQ(fingerprint(), before);
}

}  // namespace
}  // namespace cenote::client::test
