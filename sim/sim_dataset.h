// sim_dataset.h: writes a simulated sequence to disk as an EuRoC-layout dataset with ground truth.
//   DIR/mav0/cam{0,1}/data.csv            "#timestamp [ns],filename", rows "<ns>,<ns>.png"
//   DIR/mav0/cam{0,1}/data/<ns>.png       8-bit BGR (EuRoC's own are grey; colour gives fused points colours)
//   DIR/mav0/cam{0,1}/sensor.yaml         EuRoC format: T_BS (camera to body), intrinsics, radtan distortion
//   DIR/mav0/state_groundtruth_estimate0/data.csv   body pose, velocity and (zero) biases, EuRoC columns,
//                                         at groundtruth_rate_hz from 0.1 s before the first image to 0.1 s
//                                         after the last
//   DIR/groundtruth/body.tum              the same body poses, TUM text (t tx ty tz qx qy qz qw, seconds)
//   DIR/groundtruth/cam0.tum              left camera poses at the image timestamps
//   DIR/groundtruth/depth/<ns>.pfm        left camera depth, metres along the optical axis, +inf = none
//   DIR/groundtruth/surface.ply           points on every mesh triangle that some left image sees,
//                                         about surface_spacing_m apart, coloured with the surface albedo
//   DIR/groundtruth/calibration.yaml      the rig in the project's layout (writeStereoCalibration)
// With sim.drift (`cenote sim --drift`; the model in vio_drift.h):
//   DIR/vio_trajectory.tum                left camera poses a drifting VIO reported live, TUM, at the
//                                         image timestamps
//   DIR/loop_closures/<t>.tum             one file per correction event, named by the time it became
//                                         known (seconds, 6 decimals, the images' clock): the corrected
//                                         left camera pose of every frame up to then
// Threads: frames are rendered and written on all OpenMP threads; the files are identical whatever
// the thread count.
#pragma once

#include <functional>
#include <string>

#include "sim/simulator.h"

namespace cenote::sim {

struct SimDatasetSummary {
  int frames = 0;
  size_t surface_points = 0;
  double render_ms_per_frame = 0.0;  // rendering both cameras (CPU time summed over threads / frames)
  double write_ms_per_frame = 0.0;   // encoding and writing the frame's files (same)
  double wall_s = 0.0;               // whole run
};

// Renders every frame of `sim` and writes the layout above into out_dir (created when missing;
// existing files of the same names are replaced).
// @param progress called with the number of frames done so far (from one thread at a time).
// @throws cenote::Error when a file cannot be written.
SimDatasetSummary writeSimDataset(const Simulator& sim, const std::string& out_dir,
                                  const std::function<void(int)>& progress = {});

// Points on the given mesh triangles, about spacing_m apart (k x k sub-triangle centroids per
// triangle, k ~ sqrt(area) / spacing), with RGB colours of the surface albedo, in mesh order.
// Threads: OpenMP over runs of triangles; the same result on any thread count.
void sampleSurface(const Simulator& sim, const std::vector<uint8_t>& triangle_seen, double spacing_m,
                   std::vector<Eigen::Vector3f>& points, std::vector<std::array<uint8_t, 3>>& colors);

}  // namespace cenote::sim
