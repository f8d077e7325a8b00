#include "pipeline/fusion/depth_fusion.h"

#include <gtest/gtest.h>
#include <hwy/targets.h>
#include <omp.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <sstream>

#include "common/error.h"
#include "tests/support/fusion_reference.h"
#include "tests/support/synthetic_scene.h"

namespace cenote::pipeline {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

// Small views with every pixel empty; tests set the few pixels they need.
// 31 x 11 pixels, f = 100 px, principal point (15, 5): pixel (15, 5) looks straight ahead.
DepthFrame emptyView(double x_m = 0.0) {
  DepthFrame f;
  f.depth = cv::Mat(11, 31, CV_32F, cv::Scalar(kInf));
  f.confidence = cv::Mat(11, 31, CV_32F, cv::Scalar(0.0f));
  f.K << 100.0, 0.0, 15.0, 0.0, 100.0, 5.0, 0.0, 0.0, 1.0;
  f.T_world_cam.translation() = Eigen::Vector3d(x_m, 0.0, 0.0);
  return f;
}

void set(DepthFrame& f, int x, int y, float depth_m, float confidence) {
  f.depth.at<float>(y, x) = depth_m;
  f.confidence.at<float>(y, x) = confidence;
}

// Three views at one pose, each with one depth at the centre pixel.
std::vector<DepthFrame> stacked(float z0, float c0, float z1, float c1, float z2, float c2) {
  std::vector<DepthFrame> views(3, emptyView());
  for (auto& v : views) {
    v.depth = v.depth.clone();
    v.confidence = v.confidence.clone();
  }
  set(views[0], 15, 5, z0, c0);
  set(views[1], 15, 5, z1, c1);
  set(views[2], 15, 5, z2, c2);
  return views;
}

TEST(FuseViews, SupportedPointIsConfidenceWeightedAverageWithSummedConfidence) {
  const auto views = stacked(2.02f, 0.5f, 2.0f, 0.8f, 2.05f, 0.6f);
  const DepthFrame fused = fuseViews(views, FusionConfig{});
  const float expected_depth = (0.5f * 2.02f + 0.8f * 2.0f + 0.6f * 2.05f) / (0.5f + 0.8f + 0.6f);
  EXPECT_FLOAT_EQ(fused.depth.at<float>(5, 15), expected_depth);
  EXPECT_FLOAT_EQ(fused.confidence.at<float>(5, 15), 0.5f + 0.8f + 0.6f);
}

TEST(FuseViews, CandidateBeyondEpsDoesNotSupport) {
  // eps = 4 % of depth: 2.1 is outside the radius of 2.0 (8 cm) and of 2.01 (8.04 cm), and lies
  // behind, so it neither supports nor occludes them; their point lies in front of view 2's
  // surface there (a free-space violation of view 2), which costs each view 2's confidence 0.6.
  // Both candidates then have 0.5 + 0.8 - 0.6; the tie goes to the earlier view (0), same average.
  const auto views = stacked(2.01f, 0.5f, 2.0f, 0.8f, 2.1f, 0.6f);
  const DepthFrame fused = fuseViews(views, FusionConfig{});
  EXPECT_FLOAT_EQ(fused.depth.at<float>(5, 15), (0.5f * 2.01f + 0.8f * 2.0f) / 1.3f);
  EXPECT_FLOAT_EQ(fused.confidence.at<float>(5, 15), 0.5f + 0.8f - 0.6f);
}

TEST(FuseViews, AbsoluteSupportRadiusIsInMetres) {
  FusionConfig config;
  config.support_radius = SupportRadius::kAbsolute;
  config.eps = 0.15;  // 2.1 is now within
  const auto views = stacked(2.01f, 0.5f, 2.0f, 0.8f, 2.1f, 0.6f);
  const DepthFrame fused = fuseViews(views, config);
  EXPECT_FLOAT_EQ(fused.confidence.at<float>(5, 15), 1.9f);
  EXPECT_FLOAT_EQ(fused.depth.at<float>(5, 15), (0.5f * 2.01f + 0.8f * 2.0f + 0.6f * 2.1f) / 1.9f);
}

TEST(FuseViews, OccludedCandidateLosesExactlyTheOccludersConfidence) {
  // View 0 saw a surface at 2 m in front of the reference's 3 m on the reference ray.
  const auto views = stacked(2.0f, 0.3f, 3.0f, 1.0f, 3.0f, 0.9f);
  const DepthFrame fused = fuseViews(views, FusionConfig{});
  EXPECT_FLOAT_EQ(fused.depth.at<float>(5, 15), 3.0f);
  EXPECT_FLOAT_EQ(fused.confidence.at<float>(5, 15), 1.0f + 0.9f - 0.3f);
}

TEST(FuseViews, FreeSpaceViolatorLosesExactlyTheViolatedViewsConfidence) {
  // Cameras on a line along x, 0.1 m apart; reference pixel (15, 5) sees X = (0, 0, 2).
  // View 0 (x = -0.1) agrees: its pixel (20, 5) at 2 m renders onto (15, 5).
  // View 2 (x = +0.1) sees X at pixel (10, 5) but measured 4 m there: X lies in space view 2 saw
  // empty. View 2's point at 4 m renders elsewhere (pixel 12.5), so nothing on the reference ray
  // conflicts: only the free-space test in view 2's own map can catch it.
  std::vector<DepthFrame> views = {emptyView(-0.1), emptyView(0.0), emptyView(0.1)};
  set(views[0], 20, 5, 2.0f, 0.7f);
  set(views[1], 15, 5, 2.0f, 1.0f);
  set(views[2], 10, 5, 4.0f, 0.45f);
  FusionScratch scratch;
  DepthFrame fused;
  std::vector<const DepthFrame*> pointers = {&views[0], &views[1], &views[2]};
  fuseViews(pointers, FusionConfig{}, scratch, fused);
  EXPECT_FALSE(std::isfinite(scratch.views[2].depth.at<float>(5, 15))) << "view 2 must not render onto (15, 5)";
  EXPECT_FLOAT_EQ(scratch.views[0].depth.at<float>(5, 15), 2.0f);
  EXPECT_FLOAT_EQ(fused.depth.at<float>(5, 15), 2.0f);
  EXPECT_FLOAT_EQ(fused.confidence.at<float>(5, 15), 0.7f + 1.0f - 0.45f);
}

TEST(FuseViews, RejectsBelowFusedThresholdAndKeepsAtIt) {
  FusionConfig config;
  config.min_fused_confidence = 0.5;
  auto views = stacked(kInf, 0.0f, 2.0f, 0.49f, kInf, 0.0f);
  DepthFrame fused = fuseViews(views, config);
  EXPECT_FALSE(std::isfinite(fused.depth.at<float>(5, 15)));
  EXPECT_EQ(fused.confidence.at<float>(5, 15), 0.0f);
  views = stacked(kInf, 0.0f, 2.0f, 0.5f, kInf, 0.0f);
  fused = fuseViews(views, config);
  EXPECT_EQ(fused.depth.at<float>(5, 15), 2.0f);
  EXPECT_EQ(fused.confidence.at<float>(5, 15), 0.5f);
}

TEST(FuseViews, InputBelowConfidenceFloorOrBeyondMaxDepthTakesNoPart) {
  FusionConfig config;
  config.min_input_confidence = 0.35;  // removes the occluder of confidence 0.3
  auto views = stacked(2.0f, 0.3f, 3.0f, 1.0f, 3.0f, 0.9f);
  EXPECT_FLOAT_EQ(fuseViews(views, config).confidence.at<float>(5, 15), 1.9f);
  config = FusionConfig{};
  config.max_depth_m = 2.5;  // removes the reference and view 2; the 2 m view alone is too weak
  const DepthFrame fused = fuseViews(views, config);
  EXPECT_FALSE(std::isfinite(fused.depth.at<float>(5, 15)));
}

TEST(FuseViews, ZeroAndNanDepthCountAsNone) {
  const auto views = stacked(0.0f, 1.0f, 2.0f, 1.0f, NAN, 1.0f);
  const DepthFrame fused = fuseViews(views, FusionConfig{});
  EXPECT_EQ(fused.confidence.at<float>(5, 15), 1.0f);
  EXPECT_EQ(fused.depth.at<float>(5, 15), 2.0f);
}

TEST(FuseViews, EmptyViewsGiveAnEmptyResult) {
  const std::vector<DepthFrame> views(3, emptyView());
  const DepthFrame fused = fuseViews(views, FusionConfig{});
  EXPECT_EQ(cv::countNonZero(fused.confidence), 0);
}

TEST(FuseViews, ErrorsNameTheProblem) {
  auto views = stacked(2.0f, 1.0f, 2.0f, 1.0f, 2.0f, 1.0f);
  auto message = [](const std::vector<DepthFrame>& v, FusionConfig config = {}) {
    try {
      fuseViews(v, config);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message({views[0], views[1]}).find("got 2 views, fusion.num_views is 3"), std::string::npos);
  FusionConfig bad;
  bad.num_views = 4;
  EXPECT_NE(message(views, bad).find("fusion.num_views = 4"), std::string::npos);

  auto nan_pose = views;
  nan_pose[2].T_world_cam.translation().x() = NAN;
  EXPECT_NE(message(nan_pose).find("non-finite"), std::string::npos) << message(nan_pose);
  auto scaled = views;
  scaled[0].T_world_cam.linear() *= 1.01;
  EXPECT_NE(message(scaled).find("not orthonormal"), std::string::npos) << message(scaled);
  auto small = views;
  small[2].depth = cv::Mat(10, 31, CV_32F, cv::Scalar(1.0f));
  small[2].confidence = cv::Mat(10, 31, CV_32F, cv::Scalar(1.0f));
  EXPECT_NE(message(small).find("is 31x10 but the other views are 31x11"), std::string::npos) << message(small);
  auto no_conf = views;
  no_conf[1].confidence.release();
  EXPECT_NE(message(no_conf).find("confidence map must be CV_32FC1"), std::string::npos);
  auto bad_k = views;
  bad_k[1].K(0, 0) = 0.0;
  EXPECT_NE(message(bad_k).find("intrinsic matrix"), std::string::npos);
}

// A noisy window of the box scene (occlusion edges), N_f views.
std::vector<DepthFrame> noisyBoxWindow(int n_views, uint32_t seed) {
  const test::Scene scene = test::boxScene();
  const test::TestCamera camera;
  const auto poses = test::surveyPoses(n_views, 0.12);
  std::vector<DepthFrame> views;
  for (int i = 0; i < n_views; ++i) {
    DepthFrame view = test::renderScene(scene, camera, poses[i], i);
    const test::NoisyDepth noisy = test::addStereoNoise(view.depth, test::StereoNoise{}, seed + i);
    view.depth = noisy.depth;
    view.confidence = noisy.confidence;
    views.push_back(view);
  }
  return views;
}

TEST(FuseViews, ImagesNarrowerThanAVectorFollowTheSameRules) {
  // Three columns: narrower than any SIMD vector, so the scalar path runs.
  const auto wide = noisyBoxWindow(3, 300);
  std::vector<DepthFrame> views;
  for (const DepthFrame& w : wide) {
    DepthFrame v = w;
    const cv::Rect columns(150, 0, 3, w.depth.rows);
    v.depth = w.depth(columns).clone();
    v.confidence = w.confidence(columns).clone();
    v.color = w.color(columns).clone();
    v.K(0, 2) -= columns.x;
    views.push_back(v);
  }
  const DepthFrame fast = fuseViews(views, FusionConfig{});
  const DepthFrame plain = test::fuseViewsReference({&views[0], &views[1], &views[2]}, FusionConfig{});
  int valid = 0;
  for (int y = 0; y < fast.depth.rows; ++y) {
    for (int x = 0; x < fast.depth.cols; ++x) {
      const float a = fast.depth.at<float>(y, x), b = plain.depth.at<float>(y, x);
      valid += std::isfinite(a);
      EXPECT_TRUE((std::isinf(a) && std::isinf(b)) || std::abs(a - b) <= 1e-4f * b)
          << "pixel (" << x << ", " << y << "): " << a << " vs " << b;
    }
  }
  EXPECT_GT(valid, fast.depth.rows);
}

TEST(FuseViews, OneAndTwoThreadsAreBitIdentical) {
  for (int n_views : {3, 5}) {
    const auto views = noisyBoxWindow(n_views, 100);
    FusionConfig config;
    config.num_views = n_views;
    const int threads = omp_get_max_threads();
    omp_set_num_threads(1);
    const DepthFrame one = fuseViews(views, config);
    omp_set_num_threads(2);
    const DepthFrame two = fuseViews(views, config);
    omp_set_num_threads(threads);
    ASSERT_EQ(one.depth.size(), two.depth.size());
    const size_t bytes = one.depth.total() * sizeof(float);
    EXPECT_EQ(std::memcmp(one.depth.data, two.depth.data, bytes), 0) << "depth differs, N_f = " << n_views;
    EXPECT_EQ(std::memcmp(one.confidence.data, two.confidence.data, bytes), 0) << "confidence differs, N_f = " << n_views;
    EXPECT_GT(cv::countNonZero(one.confidence), static_cast<int>(one.depth.total() / 2));
  }
}

// Pixels where two fused frames differ in depth or confidence: by any bit (tolerance 0), or by
// more than `tolerance` of the depth and in confidence.
int differingPixels(const DepthFrame& a, const DepthFrame& b, float tolerance) {
  int count = 0;
  for (int y = 0; y < a.depth.rows; ++y) {
    for (int x = 0; x < a.depth.cols; ++x) {
      const float za = a.depth.at<float>(y, x), zb = b.depth.at<float>(y, x);
      const float ca = a.confidence.at<float>(y, x), cb = b.confidence.at<float>(y, x);
      if (tolerance == 0.0f) {
        count += std::memcmp(&za, &zb, sizeof(float)) != 0 || std::memcmp(&ca, &cb, sizeof(float)) != 0;
      } else {
        count += !((std::isinf(za) && std::isinf(zb)) ||
                   (std::abs(za - zb) <= tolerance * zb && std::abs(ca - cb) <= tolerance));
      }
    }
  }
  return count;
}

// Every instruction set with fused multiply-add (AVX2, AVX-512, NEON, SVE) gives the same bits
// (N_f = 3 and 5 have kernels of their own, 7 takes the general one). SSSE3 and SSE4 have no FMA:
// Highway rounds their MulAdd twice, so every rendered depth may differ in its last bit (about a
// tenth of the fused pixels do), and a decision that sits on a boundary may flip, as between the
// float kernels and the double reference below.
TEST(FuseViews, EveryInstructionSetWithFmaGivesTheSameBits) {
  constexpr int64_t kNoFma = HWY_SSSE3 | HWY_SSE4 | HWY_EMU128 | HWY_SCALAR;
  const std::vector<int64_t> targets = hwy::SupportedAndGeneratedTargets();  // before any is forced
  for (int n_views : {3, 5, 7}) {
    const auto views = noisyBoxWindow(n_views, 300);
    FusionConfig config;
    config.num_views = n_views;
    DepthFrame first;
    std::string first_name;
    int compared = 0;
    for (const int64_t target : targets) {
      if (target == HWY_SCALAR) continue;  // never chosen: images narrower than a vector take the scalar path
      hwy::SetSupportedTargetsForTest(target);
      const DepthFrame fused = fuseViews(views, config);
      if (first.depth.empty()) {
        ASSERT_EQ(target & kNoFma, 0) << "the best instruction set comes first";
        first = fused;
        first_name = hwy::TargetName(target);
        EXPECT_GT(cv::countNonZero(fused.confidence), static_cast<int>(fused.depth.total() / 2));
        continue;
      }
      const bool fma = (target & kNoFma) == 0;
      const int differ = differingPixels(first, fused, fma ? 0.0f : 1e-4f);
      std::printf("[fusion %s vs %s] N_f = %d: %d of %zu pixels differ%s\n", hwy::TargetName(target), first_name.c_str(),
                  n_views, differ, fused.depth.total(), fma ? "" : " by more than 1e-4");
      if (fma) {
        EXPECT_EQ(differ, 0) << hwy::TargetName(target) << " vs " << first_name << ", N_f = " << n_views;
        ++compared;
      } else {
        EXPECT_LE(differ, static_cast<int>(fused.depth.total() / 2000))
            << hwy::TargetName(target) << " vs " << first_name << ", N_f = " << n_views;
      }
    }
    if (first_name == "AVX3") {
      EXPECT_GE(compared, 1) << "AVX2 was not compared with AVX-512";
    }
  }
  hwy::SetSupportedTargetsForTest(0);
}

TEST(FuseViews, AgreesWithThePlainReferenceImplementation) {
  for (int n_views : {3, 5}) {
    const auto views = noisyBoxWindow(n_views, 200);
    FusionConfig config;
    config.num_views = n_views;
    const DepthFrame fast = fuseViews(views, config);
    std::vector<const DepthFrame*> pointers;
    for (const auto& v : views) pointers.push_back(&v);
    const DepthFrame plain = test::fuseViewsReference(pointers, config);
    int disagree = 0;
    std::ostringstream examples;
    for (int y = 0; y < fast.depth.rows; ++y) {
      for (int x = 0; x < fast.depth.cols; ++x) {
        const float a = fast.depth.at<float>(y, x), b = plain.depth.at<float>(y, x);
        const bool same = (std::isinf(a) && std::isinf(b)) ||
                          (std::abs(a - b) <= 1e-4f * b &&
                           std::abs(fast.confidence.at<float>(y, x) - plain.confidence.at<float>(y, x)) <= 1e-4f);
        if (!same && ++disagree <= 3) {
          examples << "\n  pixel (" << x << ", " << y << "): depth " << a << " vs " << b << ", confidence "
                   << fast.confidence.at<float>(y, x) << " vs " << plain.confidence.at<float>(y, x);
        }
      }
    }
    // float vs double arithmetic may flip a decision that sits exactly on a boundary.
    // (A z-buffer tie or a point on a pixel border then changes the candidates of that pixel.)
    EXPECT_LE(disagree, static_cast<int>(fast.depth.total() / 2000)) << "N_f = " << n_views << examples.str();
    std::printf("[fusion vs plain reference] N_f = %d: %d of %zu pixels differ\n", n_views, disagree, fast.depth.total());
  }
}

}  // namespace
}  // namespace cenote::pipeline
