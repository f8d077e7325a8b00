// The stereo engine on simulated pairs: the simulator's images carry enough texture and consistent
// enough radiometry that default SGM gets the disparity (from ground-truth depth, d = f b / Z) right.
#include <gtest/gtest.h>

#include "sim/rasterizer.h"
#include "sim/simulator.h"
#include "pipeline/stereo/stereo_matcher.h"

namespace cenote::sim {
namespace {

struct Bad2 {
  double bad2_percent = 0.0;
  int evaluated = 0;
};

// Pixels with ground truth inside the search range, whose match is inside the right image and
// not occluded there (the right camera sees the same depth at x - d).
Bad2 evaluate(const Simulator& sim, const SimFrame& frame, const cv::Mat& disparity, int num_disparities) {
  const PinholeCamera& cam = sim.rig().camera;
  const double fb = cam.fx * sim.rig().baseline_m;
  const VisibilityBuffer right = rasterize(sim.scene().mesh, cam, frame.T_world_cam1);
  Bad2 out;
  int bad = 0;
  for (int y = 0; y < frame.depth.rows; ++y) {
    for (int x = 0; x < frame.depth.cols; ++x) {
      const float z = frame.depth.at<float>(y, x);
      if (!std::isfinite(z)) continue;
      const double d = fb / z;
      if (d >= num_disparities - 1 || x - d < 0) continue;
      const float z_right = right.depth.at<float>(
          y, static_cast<int>(std::lround(x - d)) < 0 ? 0 : static_cast<int>(std::lround(x - d)));
      if (!(std::abs(z_right - z) < 0.02 * z)) continue;  // occluded in the right image
      ++out.evaluated;
      const float est = disparity.at<float>(y, x);
      if (!std::isfinite(est) || std::abs(est - d) > 2.0) ++bad;
    }
  }
  out.bad2_percent = out.evaluated ? 100.0 * bad / out.evaluated : 100.0;
  return out;
}

class SimStereo : public ::testing::TestWithParam<SimSceneKind> {};

TEST_P(SimStereo, DefaultSgmBad2IsUnderTenPercent) {
  SimConfig config;  // 800x600, baseline 0.12 m, noise 2 grey levels
  config.scene = GetParam();
  config.num_frames = 12;
  const Simulator sim(config);
  // The default matcher without the mapping filters (left-right check, truncated columns), which
  // trade density for fewer wrong pixels and would count here as bad.
  pipeline::StereoConfig stereo;
  stereo.lr_check = false;
  stereo.invalidate_truncated = false;
  pipeline::StereoMatcher matcher{stereo};
  ASSERT_EQ(matcher.config().num_disparities, 112);
  for (int index : {0, 11}) {
    const SimFrame frame = sim.renderFrame(index);
    const pipeline::DisparityMap result = matcher.match(frame.left, frame.right);
    const Bad2 stats = evaluate(sim, frame, result.disparity, matcher.config().num_disparities);
    EXPECT_GT(stats.evaluated, 100000) << toString(GetParam()) << " frame " << index;
    EXPECT_LT(stats.bad2_percent, 10.0) << toString(GetParam()) << " frame " << index << ": bad-2 " << stats.bad2_percent
                                        << " % of " << stats.evaluated << " pixels";
    std::printf("[ sim stereo ] %s frame %d: bad-2 %.2f %% of %d pixels\n", toString(GetParam()), index, stats.bad2_percent,
                stats.evaluated);
  }
}

INSTANTIATE_TEST_SUITE_P(Scenes, SimStereo,
                         ::testing::Values(SimSceneKind::kCave, SimSceneKind::kReef, SimSceneKind::kWreck),
                         [](const auto& info) { return std::string(toString(info.param)); });

}  // namespace
}  // namespace cenote::sim
