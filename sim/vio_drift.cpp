#include "sim/vio_drift.h"

#include <cmath>

#include "sim/procedural_noise.h"

namespace cenote::sim {
namespace {

constexpr uint64_t kDriftStream = 0x5649'4f44'5249'4654ULL;  // "VIODRIFT": apart from the scene's streams

// A standard normal sample from two hashed uniforms (Box-Muller), for draw `k` of frame `i`.
double gaussian(uint64_t seed, int i, int k) {
  const double u1 = 1.0 - hashToUnit(hash64(seed, kDriftStream, static_cast<uint64_t>(i), 2 * k));
  const double u2 = hashToUnit(hash64(seed, kDriftStream, static_cast<uint64_t>(i), 2 * k + 1));
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
}

struct Bias {
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
  double yaw_rad = 0.0;
  Bias scaled(double r) const { return {position_m * r, yaw_rad * r}; }
};

Eigen::Isometry3d drifted(const Bias& bias, const Eigen::Vector3d& pivot, const Eigen::Isometry3d& T_world_cam) {
  Eigen::Isometry3d D = Eigen::Isometry3d::Identity();
  D.linear() = Eigen::AngleAxisd(bias.yaw_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  D.translation() = pivot - D.linear() * pivot + bias.position_m;
  return D * T_world_cam;
}

}  // namespace

VioDrift simulateVioDrift(const Simulator& sim) {
  const SimConfig& c = sim.config();
  const int n = sim.numFrames();
  const double dt = 1.0 / c.rate_hz;
  const double sigma_p = c.drift_position_m_per_sqrt_s * std::sqrt(dt);
  const double sigma_yaw = c.drift_yaw_deg_per_sqrt_s * M_PI / 180.0 * std::sqrt(dt);
  const auto seed = static_cast<uint64_t>(c.seed);
  const Eigen::Vector3d pivot = sim.T_world_cam0(sim.frameTimeS(0)).translation();

  VioDrift out;
  out.live.reserve(n);
  std::vector<Bias> biases;
  biases.reserve(n);
  std::vector<Eigen::Isometry3d> truth;
  truth.reserve(n);
  Bias bias;
  // The residual a frame keeps once a loop closure has corrected it; later events give it the
  // same corrected pose (a pose graph barely moves what it has already closed).
  std::vector<Bias> residuals;
  int next_event = 1;
  for (int i = 0; i < n; ++i) {
    if (i > 0) {
      for (int k = 0; k < 3; ++k) bias.position_m[k] += sigma_p * gaussian(seed, i, k);
      bias.yaw_rad += sigma_yaw * gaussian(seed, i, 3);
    }
    truth.push_back(sim.T_world_cam0(sim.frameTimeS(i)));
    biases.push_back(bias);
    out.live.push_back(drifted(bias, pivot, truth.back()));
    // 1e-9: a period that is a whole number of frames falls on that frame, not the next.
    if (c.loop_closure_period_s > 0.0 && sim.frameTimeS(i) + 1e-9 >= next_event * c.loop_closure_period_s) {
      while (residuals.size() <= static_cast<size_t>(i)) {
        residuals.push_back(biases[residuals.size()].scaled(c.loop_closure_residual));
      }
      LoopClosureEvent event;
      event.frame = i;
      event.corrected.reserve(i + 1);
      for (int j = 0; j <= i; ++j) event.corrected.push_back(drifted(residuals[j], pivot, truth[j]));
      out.events.push_back(std::move(event));
      bias = residuals[i];
      while (next_event * c.loop_closure_period_s <= sim.frameTimeS(i) + 1e-9) ++next_event;
    }
  }
  return out;
}

}  // namespace cenote::sim
