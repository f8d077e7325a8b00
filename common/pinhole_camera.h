// pinhole_camera.h: an undistorted pinhole camera, its image size and intrinsics: what the
// simulator's rasterizer and the mapping tests' analytic renderer project through.
// Units: pixels. Frame: x right, y down, z forward; the ray through the centre of pixel (u, v) is
// ((u - cx) / fx, (v - cy) / fy, 1).
// Threads: a plain value.
#pragma once

namespace cenote {

struct PinholeCamera {
  int width = 0, height = 0;
  double fx = 0.0, fy = 0.0, cx = 0.0, cy = 0.0;
};

}  // namespace cenote
