#include "eval/cloud/cloud_metrics.h"

#include <gtest/gtest.h>

#include <omp.h>

#include <random>

#include "common/error.h"

namespace cenote::eval {
namespace {

std::vector<Eigen::Vector3f> grid(int n, float spacing) {
  std::vector<Eigen::Vector3f> points;
  for (int x = 0; x < n; ++x) {
    for (int y = 0; y < n; ++y) {
      for (int z = 0; z < n; ++z) points.emplace_back(x * spacing, y * spacing, z * spacing);
    }
  }
  return points;
}

TEST(CloudMetrics, EmptyCloudIsAnError) {
  EXPECT_THROW(evaluateClouds({}, {{0, 0, 0}}), Error);
  EXPECT_THROW(evaluateClouds({{0, 0, 0}}, {}), Error);
  EXPECT_THROW(nearestDistances({{0, 0, 0}}, {}), Error);
}

TEST(CloudMetrics, IdenticalCloudsArePerfect) {
  const auto points = grid(6, 0.3f);
  const CloudEvaluation e = evaluateClouds(points, points);
  EXPECT_EQ(e.accuracy_m, 0.0);
  EXPECT_EQ(e.completeness_m, 0.0);
  EXPECT_EQ(e.precision, 1.0);
  EXPECT_EQ(e.recall, 1.0);
  EXPECT_EQ(e.fscore, 1.0);
}

TEST(CloudMetrics, ShiftedCopyHasAccuracyEqualToShift) {
  // Grid spacing 1 m, shift 0.03 m along a diagonal: every nearest neighbour is the shifted twin.
  const auto target = grid(8, 1.0f);
  const Eigen::Vector3f shift = Eigen::Vector3f(1, 2, 2) * 0.01f;  // |shift| = 0.03
  std::vector<Eigen::Vector3f> source;
  for (const auto& p : target) source.push_back(p + shift);
  const CloudEvaluation e = evaluateClouds(source, target);
  EXPECT_NEAR(e.accuracy_m, 0.03, 1e-6);
  EXPECT_NEAR(e.completeness_m, 0.03, 1e-6);
  EXPECT_EQ(e.precision, 1.0);
  CloudEvaluationOptions tight;
  tight.threshold_m = 0.02;
  EXPECT_EQ(evaluateClouds(source, target, tight).precision, 0.0);
}

TEST(CloudMetrics, HandComputedPrecisionRecall) {
  // Source->target distances: 0.05, 0.05, 0.5, 0.08 -> 3 of 4 below 0.1: precision 0.75.
  // Target->source distances: 0.05, 0.08, sqrt(20^2 + 0.05^2) -> 2 of 3 below 0.1: recall 2/3.
  // F = 2 * 0.75 * 2/3 / (0.75 + 2/3) = 1 / (17/12) = 12/17.
  const std::vector<Eigen::Vector3f> target = {{0, 0, 0}, {10, 0, 0}, {0, 0, 20}};
  const std::vector<Eigen::Vector3f> source = {{0.05f, 0, 0}, {-0.05f, 0, 0}, {0, 0.5f, 0}, {10, 0.08f, 0}};
  const CloudEvaluation e = evaluateClouds(source, target);
  EXPECT_NEAR(e.accuracy_m, (0.05 + 0.05 + 0.5 + 0.08) / 4.0, 1e-7);
  EXPECT_NEAR(e.completeness_m, (0.05 + 0.08 + std::sqrt(400.0025)) / 3.0, 1e-6);
  EXPECT_DOUBLE_EQ(e.precision, 0.75);
  EXPECT_DOUBLE_EQ(e.recall, 2.0 / 3.0);
  EXPECT_NEAR(e.fscore, 12.0 / 17.0, 1e-12);
}

TEST(CloudMetrics, ThresholdIsStrictAndCurvesIncrease) {
  const CloudEvaluation e = evaluateDistances({0.1, 0.2, 0.3, 0.4}, {0.1, 0.1}, {0.2, 0.4, 4});
  EXPECT_DOUBLE_EQ(e.precision, 0.25);  // 0.2 is not < 0.2
  EXPECT_DOUBLE_EQ(e.recall, 1.0);
  ASSERT_EQ(e.curve.size(), 4u);
  EXPECT_DOUBLE_EQ(e.curve[0].threshold_m, 0.1);
  EXPECT_DOUBLE_EQ(e.curve[0].precision, 0.0);
  EXPECT_DOUBLE_EQ(e.curve[0].recall, 0.0);
  EXPECT_DOUBLE_EQ(e.curve[0].fscore, 0.0);
  EXPECT_DOUBLE_EQ(e.curve[3].threshold_m, 0.4);
  EXPECT_DOUBLE_EQ(e.curve[3].precision, 0.75);
  for (size_t i = 1; i < e.curve.size(); ++i) EXPECT_GE(e.curve[i].precision, e.curve[i - 1].precision);
  EXPECT_THROW(evaluateDistances({1.0}, {1.0}, {0.0, 0.0, 10}), Error);
  EXPECT_THROW(evaluateDistances({1.0}, {1.0}, {0.1, -1.0, 10}), Error);
}

TEST(CloudMetrics, TwoMillionPointsMatchBruteForceOnASubsetWhateverTheThreads) {
  std::mt19937 rng(42);
  std::uniform_real_distribution<float> u(-10.0f, 10.0f);
  std::vector<Eigen::Vector3f> target(2'000'000), source(2'000'000);
  for (auto& p : target) p = {u(rng), u(rng), u(rng)};
  for (auto& p : source) p = {u(rng), u(rng), u(rng)};
  const std::vector<double> distances = nearestDistances(source, target);
  ASSERT_EQ(distances.size(), source.size());
  for (size_t i = 0; i < source.size(); i += 40'000) {
    double best = std::numeric_limits<double>::infinity();
    for (const auto& t : target) best = std::min(best, (source[i].cast<double>() - t.cast<double>()).norm());
    EXPECT_NEAR(distances[i], best, 1e-9) << "source point " << i;
  }
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  const std::vector<Eigen::Vector3f> head(source.begin(), source.begin() + 100'000);
  const std::vector<double> single = nearestDistances(head, target);
  omp_set_num_threads(threads);
  for (size_t i = 0; i < head.size(); ++i) ASSERT_EQ(single[i], distances[i]) << "source point " << i;
}

}  // namespace
}  // namespace cenote::eval
