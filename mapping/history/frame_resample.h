// frame_resample.h: a stored frame's voxel updates moved rigidly to another pose, without marching
// its rays again (map.correction_move: resample; map_history.h). A moved frame's updates are the
// ones its march made at the pose it was marched at, carried by the rigid move of the world
// T_new_old = T_world_cam_new * T_world_cam_old^-1:
//  - free: pulled, voxel by voxel: a voxel of the new pose is free when the old voxel holding its
//    centre, moved back (T_new_old^-1), was free, and so was the old voxel one voxel further along
//    its ray from the new origin (the guard). Every voxel of the moved region is sampled once, so a
//    rotation leaves no holes (pushing each old voxel forward would). The guard keeps the free set
//    from reaching a voxel past the surface where the march's rays stop: without it, a surface
//    voxel the march at the new pose hits could be made free by the pull's rounding (the 300-frame
//    correction_bench: 178 of 105577 occupied voxels of the map from scratch made free, 55 with
//    the guard, 42 with the march; agreement 0.9971 and 0.9968);
//  - hit: pushed: the voxel holding each old hit voxel's centre, moved, is hit, with that voxel's
//    colour (the first one's where two land in one voxel);
//  - occupied wins as in a march (free &= ~hit).
// How close to a march at the new pose: the answers differ only within about a voxel of the
// boundaries of the old free and hit sets (the free cone's edges, the surface): where the points
// lay inside their hit voxel is not stored, so a hit lands in the voxel of its old voxel's centre,
// up to a voxel from the march's. A move by whole voxels without rotation (a move of nothing among
// them) maps voxels onto voxels: it has no guard and shifts the old updates exactly, so a frame
// moved back to the pose it was marched at gets its marched updates back.
// Ragged free sets (rays about a voxel apart, holes in the depth) have edges everywhere: there the
// resampled map errs much more (docs/CORRECTIONS.md).
// (tests/mapping/history/frame_resample_test.cpp; the map's agreement: map_history_test.cpp.)
// Units: the updates in voxel indices; poses, the origin and voxel_size_m in metres, world frame.
// Threads: a pure function.
#pragma once

#include <Eigen/Geometry>

#include "mapping/history/frame_codec.h"

namespace cenote::mapping::history {

// `updates` (all of a frame's blocks, keys ascending, as decodeUpdates gives them) moved by
// T_new_old, its rays' origin at origin_new_m after the move: the result's keys ascending, each
// block with at least one bit set, a colour for each hit voxel of a coloured frame. Voxels that
// would leave the map's index range are dropped. Empty updates: empty updates.
FrameUpdates resampleUpdates(const FrameUpdates& updates, const Eigen::Isometry3d& T_new_old,
                             const Eigen::Vector3d& origin_new_m, double voxel_size_m);

}  // namespace cenote::mapping::history
