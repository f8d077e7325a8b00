// outlier_removal_test.cpp: PCL's statistical outlier removal (outlier_removal.h) against a brute-force
// reference of the rule it documents (Rusu et al. 2008): mean distance to the k nearest neighbours,
// kept when <= mean + mul * sample standard deviation of those means.
#include "pipeline/fusion/outlier_removal.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "common/error.h"

namespace cenote::pipeline {
namespace {

std::vector<size_t> referenceKept(const std::vector<Eigen::Vector3f>& p, int k, double mul) {
  const size_t n = p.size();
  std::vector<double> mean_d(n);
  for (size_t i = 0; i < n; ++i) {
    std::vector<double> d;
    for (size_t j = 0; j < n; ++j) {
      if (j != i) d.push_back((p[i] - p[j]).cast<double>().norm());
    }
    std::partial_sort(d.begin(), d.begin() + k, d.end());
    double sum = 0.0;
    for (int m = 0; m < k; ++m) sum += d[m];
    mean_d[i] = sum / k;
  }
  double sum = 0.0, sq = 0.0;
  for (double d : mean_d) {
    sum += d;
    sq += d * d;
  }
  const double mean = sum / n;
  const double stddev = std::sqrt((sq - sum * sum / n) / (n - 1));
  std::vector<size_t> kept;
  for (size_t i = 0; i < n; ++i) {
    if (mean_d[i] <= mean + mul * stddev) kept.push_back(i);
  }
  return kept;
}

PointBatch noisyPlaneWithOutliers(unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::normal_distribution<float> noise(0.0f, 0.002f);
  PointBatch b;
  b.t_s = 4.5;
  b.origin = Eigen::Vector3d(0.1, 0.2, 0.3);
  for (int i = 0; i < 600; ++i) b.points.emplace_back(u(rng), u(rng), 2.0f + noise(rng));
  for (int i = 0; i < 12; ++i) b.points.emplace_back(u(rng), u(rng), 2.3f + 0.5f * u(rng));  // floating specks
  for (size_t i = 0; i < b.points.size(); ++i)
    b.colors.push_back({static_cast<uint8_t>(i), static_cast<uint8_t>(i >> 8), 7});
  return b;
}

TEST(OutlierRemoval, TooFewPointsToJudgeComeBackUnchanged) {
  PointBatch b;
  EXPECT_TRUE(removeStatisticalOutliers(b, 8, 1.0).empty());
  b.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {50, 50, 50}};
  EXPECT_EQ(removeStatisticalOutliers(b, 4, 1.0).points, b.points);
}

TEST(OutlierRemoval, RejectsNonPositiveSettingsNamingThem) {
  PointBatch b = noisyPlaneWithOutliers(1);
  try {
    removeStatisticalOutliers(b, 0, 1.0);
    ADD_FAILURE() << "neighbours 0 accepted";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "outlier removal: neighbours = 0: must be >= 1");
  }
  EXPECT_THROW(removeStatisticalOutliers(b, 8, 0.0), Error);
}

TEST(OutlierRemoval, KeepsExactlyThePointsTheRuleKeepsWithTheirColours) {
  for (unsigned seed : {1u, 2u, 3u}) {
    const PointBatch b = noisyPlaneWithOutliers(seed);
    for (const auto& [k, mul] : {std::pair{8, 1.0}, std::pair{20, 2.0}}) {
      const std::vector<size_t> expected = referenceKept(b.points, k, mul);
      const PointBatch kept = removeStatisticalOutliers(b, k, mul);
      ASSERT_EQ(kept.size(), expected.size()) << "seed " << seed << ", k " << k << ", mul " << mul;
      for (size_t i = 0; i < expected.size(); ++i) {
        ASSERT_EQ(kept.points[i], b.points[expected[i]]) << "seed " << seed << ", kept point " << i;
        ASSERT_EQ(kept.colors[i], b.colors[expected[i]]) << "seed " << seed << ", kept point " << i;
      }
      size_t specks = 0;
      for (size_t i : expected) specks += i >= 600;
      EXPECT_EQ(specks, 0u) << "seed " << seed << ", k " << k << ": a floating speck was kept";
      EXPECT_EQ(kept.t_s, 4.5);
      EXPECT_EQ(kept.origin, b.origin);
    }
  }
}

TEST(OutlierRemoval, SameBatchSameResult) {
  const PointBatch b = noisyPlaneWithOutliers(9);
  const PointBatch first = removeStatisticalOutliers(b, 10, 1.0);
  removeStatisticalOutliers(noisyPlaneWithOutliers(10), 10, 1.0);
  const PointBatch again = removeStatisticalOutliers(b, 10, 1.0);
  EXPECT_EQ(first.points, again.points);
  EXPECT_EQ(first.colors, again.colors);
}

}  // namespace
}  // namespace cenote::pipeline
