// vio_drift.h: what a drifting VIO would have reported on a simulated dive, and the loop closures
// that correct it (the ground truth of `cenote sim --drift`; written by sim_dataset.cpp).
//   live poses: T_vio(t) = D(b(t), psi(t)) * T_world_cam0(t), where D shifts by the position bias b
//     and turns by the yaw bias psi about the world z axis through the first camera centre. Both
//     biases random-walk from 0: per frame, b += N(0, sigma_p^2 dt) per axis and psi += N(0,
//     sigma_psi^2 dt) (dt = 1 / rate_hz); sigma_p = sim.drift_position_m_per_sqrt_s, sigma_psi =
//     sim.drift_yaw_deg_per_sqrt_s.
//   loop closures: every sim.loop_closure_period_s of the dive (at the first frame at or after
//     k * period, k = 1, 2, ...), an event holds the corrected pose of every frame up to and
//     including that one: D(r b_i, r psi_i) * T_world_cam0(t_i), r = sim.loop_closure_residual
//     (the fraction of each frame's live drift the correction leaves). A frame keeps the pose its
//     first correction gave it in later events (a pose graph barely moves what it has closed), and
//     the live biases go on from the corrected frame's, as a VIO goes on from its corrected pose.
// Deterministic: a counter-based hash of sim.seed (procedural_noise.h), the same on every machine.
// Units: metres, radians inside (degrees in the config), seconds since the first frame.
// Threads: pure functions.
#pragma once

#include <Eigen/Geometry>
#include <vector>

#include "sim/simulator.h"

namespace cenote::sim {

struct LoopClosureEvent {
  int frame = 0;                             // the frame at which the correction becomes known
  std::vector<Eigen::Isometry3d> corrected;  // T_world_cam0 of frames 0..frame
};

struct VioDrift {
  std::vector<Eigen::Isometry3d> live;  // T_world_cam0 the VIO reported at each frame
  std::vector<LoopClosureEvent> events;
};

// The drift and corrections of sim's dive (SimConfig's drift_* and loop_closure_* settings).
VioDrift simulateVioDrift(const Simulator& sim);

}  // namespace cenote::sim
