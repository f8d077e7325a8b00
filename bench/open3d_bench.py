#!/ usr / bin / python3
"""open3d_bench.py: map integration of the same frames by cenote, OctoMap and Open3D, in one run.

  /usr/bin/python3 bench/open3d_bench.py build/bench/map_bench [--frames 10] [--threads 2]

map_bench --peers-only 1 integrates map_bench's frames (an 800x600 camera over a rocky sea floor,
tests/mapping/support/analytic_scene.h) into cenote's map and OctoMap's (insertPointCloud, discretize
on) and writes the same views as depth images; this script then integrates those depth images, with
the same intrinsics and poses, 5 cm voxels and the 10 m range as maximum depth, into Open3D's
VoxelBlockGrid on the CPU (compute_unique_block_coordinates + integrate, TSDF and weight, 8x8x8
blocks), and prints the three side by side: CPU time per frame (all threads of each process, with
OMP_WAIT_POLICY=passive so that idle OpenMP threads do not count) and wall time.

What each computes differs: cenote and OctoMap carve free space along every ray from the camera to
its end point and mark the end voxel occupied (occupancy log-odds, OctoMap's update rule); Open3D
updates a truncated signed distance only in a band of TRUNC_VOXELS voxels on either side of the
surface (its default, 8 x 5 cm = +-0.4 m): most of the space in front of the surface, which a
planner needs to know free, it never touches.

Open3D is optional (Debian's python3-open3d: 31 packages, about 320 MiB): without it the script says
so and exits 0 after map_bench's own rows.
"""
import argparse
import os
import re
import subprocess
import sys
import tempfile
import time

TRUNC_VOXELS = 8.0  # Open3D's default trunc_voxel_multiplier: the band is +-8 voxels


def read_frames(folder):
    """The frames map_bench wrote (bench/integration_peers.h): camera, voxel, range, depth files, poses."""
    import numpy as np
    camera, frames, voxel_m, max_range_m = None, [], None, None
    for line in open(os.path.join(folder, "frames.txt")):
        words = line.split()
        if words[0] == "camera":
            w, h = int(words[1]), int(words[2])
            camera = (w, h) + tuple(float(v) for v in words[3:7])
        elif words[0] == "voxel_m":
            voxel_m = float(words[1])
        elif words[0] == "max_range_m":
            max_range_m = float(words[1])
        elif words[0] == "frame":
            w, h = camera[0], camera[1]
            depth = np.fromfile(os.path.join(folder, words[1]), dtype="<f4")
            if depth.size != w * h:
                raise SystemExit(f"open3d_bench: {words[1]} holds {depth.size} depths for {w}x{h} pixels")
            T_world_cam = np.eye(4)
            T_world_cam[:3, :] = np.array([float(v) for v in words[2:14]]).reshape(3, 4)
            frames.append((depth.reshape(h, w), T_world_cam))
    return camera, voxel_m, max_range_m, frames


def integrate_open3d(camera, voxel_m, max_range_m, frames):
    """Open3D's TSDF integration of the frames into a fresh grid after one warm-up frame.
    Returns (CPU ms/frame, wall ms/frame, voxels with weight > 0)."""
    import numpy as np
    import open3d as o3d
    o3c = o3d.core
    device = o3c.Device("CPU:0")
    _, _, fx, fy, cx, cy = camera
    intrinsic = o3c.Tensor([[fx, 0.0, cx], [0.0, fy, cy], [0.0, 0.0, 1.0]], o3c.float64)
    images = [(o3d.t.geometry.Image(o3c.Tensor(np.ascontiguousarray(d))),
               o3c.Tensor(np.linalg.inv(T), o3c.float64)) for d, T in frames]

    def fresh_grid():
        return o3d.t.geometry.VoxelBlockGrid(attr_names=("tsdf", "weight"), attr_dtypes=(o3c.float32, o3c.float32),
                                             attr_channels=((1), (1)), voxel_size=voxel_m, block_resolution=8,
                                             block_count=60000, device=device)

    def integrate(grid, depth, extrinsic):
        blocks = grid.compute_unique_block_coordinates(depth, intrinsic, extrinsic, 1.0, max_range_m, TRUNC_VOXELS)
        grid.integrate(blocks, depth, intrinsic, extrinsic, 1.0, max_range_m, TRUNC_VOXELS)

    integrate(fresh_grid(), *images[0])  # warm-up, as map_bench does for ours
    grid = fresh_grid()
    c0, t0 = time.process_time(), time.perf_counter()
    for depth, extrinsic in images:
        integrate(grid, depth, extrinsic)
    cpu_ms = (time.process_time() - c0) * 1e3 / len(images)
    wall_ms = (time.perf_counter() - t0) * 1e3 / len(images)
    weights = grid.attribute("weight").numpy()
    return cpu_ms, wall_ms, int((weights > 0).sum())


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("map_bench", help="path of build/bench/map_bench")
    parser.add_argument("--frames", type=int, default=10)
    parser.add_argument("--threads", type=int, default=2)
    args = parser.parse_args()
    os.environ.setdefault("OMP_WAIT_POLICY", "passive")  # before Open3D's libgomp is loaded
    os.environ.setdefault("OMP_NUM_THREADS", str(args.threads))  # Open3D on the same threads as ours
    with tempfile.TemporaryDirectory() as folder:
        out = subprocess.run([args.map_bench, "--peers-only", "1", "--frames", str(args.frames), "--threads",
                              str(args.threads), "--write-frames", folder], check=True, capture_output=True,
                             text=True).stdout
        rows = {}
        for m in re.finditer(r"^\| integration \((\d+) threads?\), (CPU|wall) ms/frame \| ([\d.]+) \| ([\d.]+) \|", out,
                             re.M):
            rows[(int(m.group(1)), m.group(2))] = (float(m.group(3)), float(m.group(4)))
        if (args.threads, "CPU") not in rows:
            raise SystemExit("open3d_bench: map_bench printed no integration rows:\n" + out)
        known = re.search(r"^known voxels: (\d+) \((\d+) occupied, (\d+) free\)", out, re.M)
        ours_cpu, octo_cpu = rows[(args.threads, "CPU")]
        ours_wall, octo_wall = rows[(args.threads, "wall")]
        try:
            import open3d  # noqa: F401
        except ImportError:
            open3d = None
        o3d_row = None
        if open3d is not None:
            camera, voxel_m, max_range_m, frames = read_frames(folder)
            o3d_row = integrate_open3d(camera, voxel_m, max_range_m, frames)
    print(f"{args.frames} frames (800x600, map_bench's sea floor), 5 cm voxels, 10 m range, {args.threads} threads; "
          "CPU time of all threads of each process")
    print("\n| integration | CPU ms/frame | wall ms/frame | CPU time / cenote's | computes |\n|---|---|---|---|---|")
    print(f"| cenote OccupancyMap::integrate | {ours_cpu:.1f} | {ours_wall:.1f} | 1.0x | "
          "occupancy log-odds: free space carved along each whole ray, the end voxel hit "
          f"({known.group(1)} voxels known: {known.group(2)} occupied, {known.group(3)} free) |")
    print(f"| OctoMap insertPointCloud | {octo_cpu:.1f} | {octo_wall:.1f} | {octo_cpu / ours_cpu:.1f}x | "
          "the same occupancy update, on an octree |")
    if o3d_row is None:
        print("\nopen3d_bench: Open3D row skipped: Python module open3d not found "
              "(Debian: apt-get install python3-open3d)")
        return
    cpu, wall, voxels = o3d_row
    print(f"| Open3D {open3d.__version__} VoxelBlockGrid.integrate (CPU) | {cpu:.1f} | {wall:.1f} | {cpu / ours_cpu:.1f}x | "
          f"TSDF and weight only within +-{TRUNC_VOXELS * voxel_m:.2f} m of the surface ({voxels} voxels weighted) |")


if __name__ == "__main__":
    sys.exit(main())
