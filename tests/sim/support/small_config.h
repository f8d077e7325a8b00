// small_config.h: a small simulated dive (400x300 images, a few frames) for the simulator's tests.
// Threads: a plain value.
#pragma once

#include "sim/sim_config.h"

namespace cenote::sim::test {

inline SimConfig smallConfig(SimSceneKind scene, int frames = 6) {
  SimConfig c;
  c.scene = scene;
  c.num_frames = frames;
  c.width_px = 400;
  c.height_px = 300;
  return c;
}

}  // namespace cenote::sim::test
