// back_projection.h: turns a (fused) depth map into coloured points in the world frame.
// Units: metres; pixel (x, y) is the centre of column x, row y. Frame: world, via the frame's
// T_world_cam (p_world = T_world_cam * Z K^-1 [x y 1]^T). Colours: RGB from the BGR left image.
// Threads: OpenMP inside; the point order is row-major whatever the thread count.
#pragma once

#include "common/point_batch.h"
#include "pipeline/frame/frames.h"

namespace cenote::pipeline {

// Fills `out` with one point per pixel of finite, positive depth, in row-major order; colours when
// frame.color is not empty (else out.colors stays empty); origin = the camera centre, t_s = frame.t_s.
// `out` keeps its capacity, so a batch reused frame after frame stops allocating.
// @throws cenote::Error when depth is not CV_32FC1 or color is neither empty nor CV_8UC3 of its size.
void backProject(const DepthFrame& frame, PointBatch& out);

}  // namespace cenote::pipeline
