// A frame's stored updates moved rigidly (mapping/history/frame_resample.h): exact for a move of
// nothing and for whole voxels, no holes under rotation, and within a voxel of a march at the new pose.
#include "mapping/history/frame_resample.h"

#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "mapping/detail/block_table.h"
#include "mapping/integration/ray_batch.h"
#include "tests/mapping/support/drifted_frames.h"

namespace cenote::mapping::history {
namespace {

constexpr double kVoxel = 0.05;

using VoxelSet = std::set<std::array<int, 3>>;

// The voxels whose free (hit: false) or hit (true) bit is set.
VoxelSet voxelsOf(const FrameUpdates& u, bool hit) {
  VoxelSet out;
  for (size_t b = 0; b < u.keys.size(); ++b) {
    const BlockIndex block = detail::unpackIndex(u.keys[b]);
    for (int o = 0; o < kBlockVoxels; ++o) {
      const uint64_t word = hit ? u.masks[b].hit[o >> 6] : u.masks[b].free[o >> 6];
      if ((word >> (o & 63)) & 1) {
        const VoxelIndex v = voxelOfOffset(block, o);
        out.insert({v.x(), v.y(), v.z()});
      }
    }
  }
  return out;
}

Eigen::Isometry3d roomView() { return test::lookAt(Eigen::Vector3d(0.3, -0.2, 0.1), Eigen::Vector3d(2.0, 1.0, -0.3)); }

// The updates a ray march makes of the room seen from roomView(), its points and origin moved by
// T_new_old (where a correction puts them).
FrameUpdates marchedAt(const Eigen::Isometry3d& T_new_old = Eigen::Isometry3d::Identity()) {
  const PinholeCamera camera{.width = 96, .height = 72, .fx = 70.0, .fy = 70.0, .cx = 47.5, .cy = 35.5};
  PointBatch batch = test::renderBatch(test::driftedRoom(), camera, roomView(), 8.0);
  for (Eigen::Vector3f& p : batch.points) p = (T_new_old * p.cast<double>()).cast<float>();
  batch.origin = T_new_old * batch.origin;
  RayBatch rays;
  rays.build(batch, kVoxel, 10.0, 1, 16);
  return FrameUpdates::of(rays.updates());
}

// Each block has a bit; colours belong to hit voxels, one each.
void expectWellFormed(const FrameUpdates& u) {
  for (size_t b = 0; b < u.keys.size(); ++b) {
    if (b > 0) {
      EXPECT_LT(u.keys[b - 1], u.keys[b]) << "keys not ascending at " << b;
    }
    bool any = false;
    for (int w = 0; w < 8; ++w) {
      any |= (u.masks[b].free[w] | u.masks[b].hit[w]) != 0;
      EXPECT_EQ(u.masks[b].free[w] & u.masks[b].hit[w], 0u) << "block " << b << " word " << w << ": free and hit";
    }
    EXPECT_TRUE(any) << "block " << b << " has no bit";
  }
  const VoxelSet hits = voxelsOf(u, true);
  VoxelSet coloured;
  for (const EndpointColor& c : u.colors) {
    EXPECT_TRUE(hits.count({c.ijk.x(), c.ijk.y(), c.ijk.z()})) << "colour of voxel " << c.ijk.transpose() << ": no hit";
    EXPECT_TRUE(coloured.insert({c.ijk.x(), c.ijk.y(), c.ijk.z()}).second) << "two colours of " << c.ijk.transpose();
  }
  EXPECT_EQ(coloured.size(), hits.size());
}

TEST(ResampleUpdates, EmptyUpdatesStayEmpty) {
  const FrameUpdates out = resampleUpdates(FrameUpdates{}, Eigen::Isometry3d::Identity(), Eigen::Vector3d::Zero(), kVoxel);
  EXPECT_TRUE(out.keys.empty() && out.masks.empty() && out.colors.empty());
}

TEST(ResampleUpdates, AMoveOfNothingReturnsTheUpdatesAsTheyWere) {
  const FrameUpdates marched = marchedAt();
  ASSERT_GT(marched.keys.size(), 50u);
  const FrameUpdates out = resampleUpdates(marched, Eigen::Isometry3d::Identity(), roomView().translation(), kVoxel);
  EXPECT_EQ(out.keys, marched.keys);
  ASSERT_EQ(out.masks.size(), marched.masks.size());
  for (size_t b = 0; b < out.masks.size(); ++b) {
    EXPECT_EQ(out.masks[b].free, marched.masks[b].free) << "block " << b;
    EXPECT_EQ(out.masks[b].hit, marched.masks[b].hit) << "block " << b;
  }
  ASSERT_EQ(out.colors.size(), marched.colors.size());
  for (size_t i = 0; i < out.colors.size(); ++i) {
    EXPECT_EQ(out.colors[i].ijk, marched.colors[i].ijk) << "colour " << i;
    EXPECT_EQ(out.colors[i].rgb, marched.colors[i].rgb) << "colour " << i;
  }
}

TEST(ResampleUpdates, AMoveByWholeVoxelsShiftsTheUpdatesExactly) {
  const FrameUpdates marched = marchedAt();
  const Eigen::Vector3i shift(3, -2, 13);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = shift.cast<double>() * kVoxel;
  const FrameUpdates out = resampleUpdates(marched, T, T * roomView().translation(), kVoxel);
  expectWellFormed(out);
  for (bool hit : {false, true}) {
    VoxelSet expected;
    for (const auto& v : voxelsOf(marched, hit)) expected.insert({v[0] + shift.x(), v[1] + shift.y(), v[2] + shift.z()});
    EXPECT_EQ(voxelsOf(out, hit), expected) << (hit ? "hit" : "free");
  }
}

// A solid free region turned by 30 degrees: every voxel whose centre, turned back, lies inside the
// region, two voxels away from its faces (the guard's voxel further along the ray from the origin
// at its centre, and a voxel of rounding), is free; a voxel-by-voxel push forward would leave holes.
TEST(ResampleUpdates, ARotatedFreeRegionHasNoHoles) {
  FrameUpdates solid;
  for (int x = 0; x < 4; ++x) {
    for (int y = 0; y < 4; ++y) {
      for (int z = 0; z < 4; ++z) {
        solid.keys.push_back(detail::packIndex(BlockIndex(x, y, z)));
        solid.masks.emplace_back().free.fill(~0ull);
      }
    }
  }
  ASSERT_TRUE(std::is_sorted(solid.keys.begin(), solid.keys.end()));
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(M_PI / 6, Eigen::Vector3d(1.0, 2.0, 2.0).normalized()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(0.013, -0.021, 0.007);
  const Eigen::Vector3d centre = Eigen::Vector3d::Constant(16 * kVoxel);  // the rays' origin, in the region
  const FrameUpdates out = resampleUpdates(solid, T, T * centre, kVoxel);
  expectWellFormed(out);
  const VoxelSet free = voxelsOf(out, false);
  const Eigen::Isometry3d back = T.inverse();
  size_t inside = 0, holes = 0, outside = 0;
  for (int x = -40; x < 72; ++x) {
    for (int y = -40; y < 72; ++y) {
      for (int z = -40; z < 72; ++z) {
        const Eigen::Vector3d p = back * ((Eigen::Vector3d(x, y, z) + Eigen::Vector3d::Constant(0.5)) * kVoxel) / kVoxel;
        const bool is_free = free.count({x, y, z}) != 0;
        if ((p.array() >= 2.0).all() && (p.array() <= 30.0).all()) {
          ++inside;
          holes += !is_free;
        }
        outside += is_free && !((p.array() >= 0.0).all() && (p.array() < 32.0).all());
      }
    }
  }
  EXPECT_GT(inside, 20000u);
  EXPECT_EQ(holes, 0u) << "of " << inside << " voxels inside";
  EXPECT_EQ(outside, 0u);  // nothing free whose centre, turned back, leaves the region
}

// A frame moved by a drift-like correction (12 cm, 3 degrees) against its march at the new pose:
// free voxels agree but for a thin shell, every hit lies within a voxel of one of the march's.
TEST(ResampleUpdates, ResampledUpdatesAreWithinAVoxelOfTheMarchAtTheNewPose) {
  Eigen::Isometry3d D = Eigen::Isometry3d::Identity();
  D.linear() = Eigen::AngleAxisd(3.0 * M_PI / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  D.translation() = Eigen::Vector3d(0.12, -0.07, 0.03);
  const FrameUpdates out = resampleUpdates(marchedAt(), D, D * roomView().translation(), kVoxel);
  expectWellFormed(out);
  const FrameUpdates march = marchedAt(D);
  const VoxelSet free = voxelsOf(out, false), march_free = voxelsOf(march, false);
  size_t both = 0;
  for (const auto& v : free) both += march_free.count(v);
  const double jaccard = double(both) / (free.size() + march_free.size() - both);
  const VoxelSet hits = voxelsOf(out, true), march_hits = voxelsOf(march, true);
  size_t far_hits = 0;
  for (const auto& v : hits) {
    bool near = false;
    for (int d = 0; d < 27 && !near; ++d)
      near = march_hits.count({v[0] + d % 3 - 1, v[1] + d / 3 % 3 - 1, v[2] + d / 9 - 1});
    far_hits += !near;
  }
  std::printf("free voxels: %zu resampled, %zu marched, %.4f in both (Jaccard); hits: %zu resampled, %zu marched, %zu "
              "beyond a voxel of the march's\n",
              free.size(), march_free.size(), jaccard, hits.size(), march_hits.size(), far_hits);
  EXPECT_GT(free.size(), 10000u);
  EXPECT_GT(jaccard, 0.9);
  EXPECT_EQ(far_hits, 0u);
  EXPECT_NEAR(double(hits.size()) / march_hits.size(), 1.0, 0.1);
}

}  // namespace
}  // namespace cenote::mapping::history
