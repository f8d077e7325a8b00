// rasterizer.h: which mesh triangle each pixel of a pinhole camera sees, and at what depth.
// A z-buffer rasteriser (no per-pixel ray tracing): chunks outside the view are culled, triangles
// crossing the near plane are clipped, and every pixel centre (x, y) inside a triangle takes the
// nearest surface. Depth is exact for the mesh: Z = d / (n . r) from the triangle's plane
// n . p = d (camera frame) and the pixel's ray r = ((x - cx) / fx, (y - cy) / fy, 1), so
// p_world = T_world_cam * (r * Z) lies on the triangle to rounding (well under a millimetre).
// Triangles are one-sided: only the side their winding's normal points to is drawn (every scene
// mesh is wound to face where the camera can be: the inside of the cave, the outside of boxes and
// hull, up from the floors; a back face is always hidden behind a front face, so culling it
// changes no pixel). Ties keep the triangle that comes first in the mesh.
// Units: pixels, metres. Frames: camera x right, y down, z forward; T_world_cam maps camera to world.
// Threads: OpenMP over mesh chunks and over fixed horizontal bands of the image; called from
// inside a parallel region (or with one thread) it draws each triangle as soon as it is set up.
// The output is bit-identical whatever the thread count (each pixel sees its triangles in mesh
// order). Calls from several threads at once are safe: the scratch buffers a call reuses are per
// calling thread.
#pragma once

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "common/pinhole_camera.h"
#include "sim/scene_mesh.h"

namespace cenote::sim {

struct VisibilityBuffer {
  cv::Mat triangle;  // CV_32S index into SceneMesh::triangles, -1 where no surface
  cv::Mat depth;     // CV_32F metres along the optical axis, +inf where no surface
};

// @param near_m surfaces nearer than this (along the optical axis) are clipped away.
// @throws cenote::Error for an empty image size or non-positive focal length.
VisibilityBuffer rasterize(const SceneMesh& mesh, const PinholeCamera& camera, const Eigen::Isometry3d& T_world_cam,
                           double near_m = 0.05);

}  // namespace cenote::sim
