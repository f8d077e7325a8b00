// Tests of pointVoxels: the voxel of each point, against toVoxel's double division, on every
// instruction set Highway compiled the kernel for.
#include "mapping/integration/point_voxels.h"

#include <gtest/gtest.h>

#include <cmath>
#include <hwy/targets.h>
#include <random>
#include <vector>

#include "mapping/integration/voxel_ray.h"

namespace cenote::mapping {
namespace {

// Checks pointVoxels against toVoxel for `points` on every target; returns the number of
// mismatches (each one reported with its point and target).
int mismatchesOnEveryTarget(const std::vector<Eigen::Vector3f>& points, double s) {
  int mismatches = 0;
  for (const int64_t target : hwy::SupportedAndGeneratedTargets()) {
    hwy::SetSupportedTargetsForTest(target);
    std::vector<VoxelIndex> out(points.size(), VoxelIndex::Constant(-7));
    pointVoxels(points.data(), points.size(), s, out.data());
    for (size_t i = 0; i < points.size(); ++i) {
      const VoxelIndex expected = toVoxel(points[i].cast<double>(), s);
      if (out[i] != expected && ++mismatches <= 10) {
        ADD_FAILURE() << hwy::TargetName(target) << ", s = " << s << ": point " << i << " (" << points[i].transpose()
                      << ") gave voxel (" << out[i].transpose() << "), toVoxel (" << expected.transpose() << ")";
      }
    }
  }
  hwy::SetSupportedTargetsForTest(0);
  return mismatches;
}

// Floats at and a few ulps around k * s for every k in [-k_max, k_max], and around integer and
// tenth metres: the quotients nearest to integers, where a product may round across one.
std::vector<Eigen::Vector3f> pointsNearFaces(double s, int k_max) {
  std::vector<float> values;
  auto around = [&](double v) {
    float f = static_cast<float>(v);
    for (int u = 0; u < 3; ++u) f = std::nextafter(f, -INFINITY);
    for (int u = 0; u < 7; ++u, f = std::nextafter(f, INFINITY)) values.push_back(f);
  };
  for (int k = -k_max; k <= k_max; ++k) around(k * s);
  for (int m = -300; m <= 300; ++m) around(m * 0.1);
  // Each value on each axis, beside others, so that every lane position sees every kind.
  std::vector<Eigen::Vector3f> points;
  for (size_t i = 0; i < values.size(); ++i) {
    points.emplace_back(values[i], values[(i * 7 + 3) % values.size()], values[(i * 13 + 5) % values.size()]);
  }
  return points;
}

TEST(PointVoxels, NoPointsWritesNothing) {
  VoxelIndex out = VoxelIndex::Constant(-7);
  pointVoxels(nullptr, 0, 0.05, &out);
  EXPECT_EQ(out, VoxelIndex::Constant(-7));
}

TEST(PointVoxels, OnePointAndZeroesMatchTheDivision) {
  EXPECT_EQ(mismatchesOnEveryTarget({Eigen::Vector3f(0.f, -0.f, 3.f)}, 0.1), 0);
  EXPECT_EQ(mismatchesOnEveryTarget({Eigen::Vector3f(-0.f, 0.f, -0.f)}, 0.05), 0);
}

TEST(PointVoxels, QuotientsNearIntegersMatchTheDivision) {
  // The product alone would be wrong on these inputs (3 / 0.1 = 29.999999999999996, 3 * 10 = 30):
  // the check is not vacuous.
  int product_wrong = 0;
  for (const double s : {0.1, 0.05, 0.02, 0.2, 0.3, 0.07, 1.0 / 3.0, 0.125, 0.01, 0.001, 2.5}) {
    const std::vector<Eigen::Vector3f> points = pointsNearFaces(s, 3000);
    for (const Eigen::Vector3f& p : points) {
      product_wrong += std::floor(static_cast<double>(p.x()) * (1.0 / s)) != toVoxel(p.cast<double>(), s).x();
    }
    EXPECT_EQ(mismatchesOnEveryTarget(points, s), 0) << "s = " << s;
  }
  EXPECT_GT(product_wrong, 50);  // 70
}

TEST(PointVoxels, PointsNearTheMapsLimitMatchTheDivision) {
  // Quotients up to kMaxVoxelIndex (checkBatch's limit), beyond which the product's error bound
  // is not used, and beyond 2^21, where the kernel hands every lane to toVoxel.
  for (const double s : {0.05, 0.001, 0.1}) {
    std::vector<Eigen::Vector3f> points;
    for (const double k : {1048000.0, 1048568.0, 1048575.5, 2097151.0, 2097152.0, 2100000.0, 4000000.0}) {
      for (const double sign : {1.0, -1.0}) {
        float f = static_cast<float>(sign * k * s);
        for (int u = 0; u < 5; ++u, f = std::nextafter(f, INFINITY)) points.emplace_back(f, -f, 0.5f * f);
      }
    }
    EXPECT_EQ(mismatchesOnEveryTarget(points, s), 0) << "s = " << s;
  }
}

TEST(PointVoxels, RandomPointsMatchTheDivision) {
  std::mt19937 rng(19);
  std::uniform_real_distribution<float> coordinate(-60.f, 60.f);
  std::vector<Eigen::Vector3f> points(100003);  // not a multiple of any lane count: a tail too
  for (Eigen::Vector3f& p : points) p = Eigen::Vector3f(coordinate(rng), coordinate(rng), coordinate(rng));
  for (const double s : {0.05, 0.1, 0.037}) EXPECT_EQ(mismatchesOnEveryTarget(points, s), 0) << "s = " << s;
}

}  // namespace
}  // namespace cenote::mapping
