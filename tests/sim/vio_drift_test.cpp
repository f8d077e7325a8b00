// The drifting VIO of `cenote sim --drift` and its loop closures, against the simulator's truth.
#include "sim/vio_drift.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <numeric>

#include "io/trajectory/tum_trajectory.h"
#include "sim/sim_dataset.h"

namespace cenote::sim {
namespace {

namespace fs = std::filesystem;

SimConfig driftConfig(int frames) {
  SimConfig c;
  c.num_frames = frames;
  c.width_px = 64;
  c.height_px = 64;
  c.drift = true;
  return c;
}

// The drift D = T_vio T_true^-1 as (position bias, yaw bias) about the pivot (vio_drift.h).
void biasOf(const Eigen::Isometry3d& vio, const Eigen::Isometry3d& truth, const Eigen::Vector3d& pivot,
            Eigen::Vector3d& position_m, double& yaw_rad) {
  const Eigen::Isometry3d D = vio * truth.inverse();
  yaw_rad = std::atan2(D.linear()(1, 0), D.linear()(0, 0));
  position_m = D.translation() - (pivot - D.linear() * pivot);
}

TEST(VioDrift, SameSeedSameDriftOtherSeedOtherDrift) {
  SimConfig c = driftConfig(60);
  const VioDrift a = simulateVioDrift(Simulator(c));
  const VioDrift b = simulateVioDrift(Simulator(c));
  c.seed = 2;
  const VioDrift other = simulateVioDrift(Simulator(c));
  ASSERT_EQ(a.live.size(), 60u);
  for (size_t i = 0; i < a.live.size(); ++i) {
    ASSERT_TRUE(a.live[i].matrix() == b.live[i].matrix()) << "frame " << i;
  }
  EXPECT_GT((a.live.back().translation() - other.live.back().translation()).norm(), 1e-4);
}

TEST(VioDrift, BiasStepsHaveTheConfiguredRandomWalkSigma) {
  SimConfig c = driftConfig(1200);
  c.loop_closure_period_s = 1000.0;  // no correction within the dive
  c.drift_position_m_per_sqrt_s = 0.05;
  c.drift_yaw_deg_per_sqrt_s = 0.5;
  const Simulator sim(c);
  const VioDrift drift = simulateVioDrift(sim);
  EXPECT_TRUE(drift.events.empty());
  const Eigen::Vector3d pivot = sim.T_world_cam0(0.0).translation();
  std::vector<double> dp, dyaw;
  Eigen::Vector3d previous_p;
  double previous_yaw = 0.0;
  for (int i = 0; i < sim.numFrames(); ++i) {
    Eigen::Vector3d p;
    double yaw;
    biasOf(drift.live[i], sim.T_world_cam0(sim.frameTimeS(i)), pivot, p, yaw);
    if (i == 0) {
      EXPECT_NEAR(p.norm(), 0.0, 1e-9);
      EXPECT_NEAR(yaw, 0.0, 1e-12);
    } else {
      for (int k = 0; k < 3; ++k) dp.push_back(p[k] - previous_p[k]);
      dyaw.push_back(yaw - previous_yaw);
    }
    previous_p = p;
    previous_yaw = yaw;
  }
  auto rms = [](const std::vector<double>& v) {
    return std::sqrt(std::inner_product(v.begin(), v.end(), v.begin(), 0.0) / v.size());
  };
  const double dt = 1.0 / c.rate_hz;
  // 3597 and 1199 samples: the sample sigma is within 5 % (4 standard errors) of the configured one.
  EXPECT_NEAR(rms(dp) / (0.05 * std::sqrt(dt)), 1.0, 0.05);
  EXPECT_NEAR(rms(dyaw) / (0.5 * M_PI / 180.0 * std::sqrt(dt)), 1.0, 0.08);
}

TEST(VioDrift, LoopClosuresLeaveTheResidualFractionOfTheDrift) {
  SimConfig c = driftConfig(100);  // 6.6 s at 15 Hz
  c.loop_closure_period_s = 2.0;
  c.loop_closure_residual = 0.1;
  c.drift_position_m_per_sqrt_s = 0.05;
  const Simulator sim(c);
  const VioDrift drift = simulateVioDrift(sim);
  ASSERT_EQ(drift.events.size(), 3u);
  const Eigen::Vector3d pivot = sim.T_world_cam0(0.0).translation();
  for (size_t e = 0; e < drift.events.size(); ++e) {
    const LoopClosureEvent& event = drift.events[e];
    EXPECT_EQ(event.frame, 30 * static_cast<int>(e + 1)) << "event " << e;
    ASSERT_EQ(event.corrected.size(), static_cast<size_t>(event.frame + 1));
    for (int j = 0; j <= event.frame; ++j) {
      Eigen::Vector3d p_corrected, p_live;
      double yaw_corrected, yaw_live;
      const Eigen::Isometry3d truth = sim.T_world_cam0(sim.frameTimeS(j));
      biasOf(event.corrected[j], truth, pivot, p_corrected, yaw_corrected);
      if (e == 0) {
        biasOf(drift.live[j], truth, pivot, p_live, yaw_live);
        EXPECT_NEAR((p_corrected - 0.1 * p_live).norm(), 0.0, 1e-9) << "frame " << j;
        EXPECT_NEAR(yaw_corrected, 0.1 * yaw_live, 1e-12) << "frame " << j;
      } else if (j <= drift.events[e - 1].frame) {
        // Corrected once, the frame keeps that pose.
        EXPECT_TRUE(event.corrected[j].isApprox(drift.events[e - 1].corrected[j], 1e-12)) << "frame " << j;
      }
    }
  }
  // The live trajectory goes on from the corrected pose: one random-walk step (sigma 0.05 m / sqrt(s)
  // over 1/15 s: 1.3 cm per axis) from it, where the drift before the correction was larger.
  Eigen::Vector3d p_next, p_corrected, p_before;
  double yaw;
  biasOf(drift.live[31], sim.T_world_cam0(sim.frameTimeS(31)), pivot, p_next, yaw);
  biasOf(drift.events[0].corrected[30], sim.T_world_cam0(sim.frameTimeS(30)), pivot, p_corrected, yaw);
  biasOf(drift.live[30], sim.T_world_cam0(sim.frameTimeS(30)), pivot, p_before, yaw);
  EXPECT_LT((p_next - p_corrected).norm(), 0.07);
  EXPECT_GT((p_before - p_corrected).norm(), (p_next - p_corrected).norm());
}

TEST(VioDrift, DatasetHoldsTheLiveTrajectoryAndOneFilePerEvent) {
  const std::string dir = (fs::temp_directory_path() / ("cenote_drift_test_" + std::to_string(::getpid()))).string();
  fs::remove_all(dir);
  SimConfig c = driftConfig(35);
  c.loop_closure_period_s = 1.0;
  const Simulator sim(c);
  writeSimDataset(sim, dir);
  const VioDrift drift = simulateVioDrift(sim);
  const io::TumTrajectory live = io::TumTrajectory::read(dir + "/vio_trajectory.tum");
  ASSERT_EQ(live.poses().size(), 35u);
  EXPECT_NEAR(live.poses()[34].t_s, sim.frameTimeNs(34) * 1e-9, 1e-6);
  EXPECT_NEAR((live.poses()[34].T_world_cam.translation() - drift.live[34].translation()).norm(), 0.0, 1e-8);
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir + "/loop_closures")) names.push_back(entry.path().filename());
  std::sort(names.begin(), names.end());
  ASSERT_EQ(names.size(), 2u);  // at 1.0 s (frame 15) and 2.0 s (frame 30)
  EXPECT_EQ(names[0], "1700000001.000000.tum");
  EXPECT_EQ(names[1], "1700000002.000000.tum");
  const io::TumTrajectory second = io::TumTrajectory::read(dir + "/loop_closures/" + names[1]);
  ASSERT_EQ(second.poses().size(), 31u);
  EXPECT_NEAR((second.poses()[30].T_world_cam.translation() - drift.events[1].corrected[30].translation()).norm(), 0.0,
              1e-8);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace cenote::sim
