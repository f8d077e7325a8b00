// make_fusion_folder: writes a small `cenote fuse` input folder from the synthetic box scene.
//   make_fusion_folder OUT_DIR
//   OUT_DIR/depth/<t>.depth.pfm, <t>.conf.pfm   noisy depth (metres, +inf = none) and confidence
//   OUT_DIR/color/<t>.png                       left image
//   OUT_DIR/traj.txt                            TUM poses (camera to world)
// Prints the intrinsics as FX,FY,CX,CY on standard output.
#include <Eigen/Geometry>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "io/image/image_io.h"
#include "tests/support/synthetic_scene.h"

int main(int argc, char** argv) {
  using namespace cenote;
  if (argc != 2) {
    std::fprintf(stderr, "usage: make_fusion_folder OUT_DIR\n");
    return 2;
  }
  const std::filesystem::path out = argv[1];
  std::filesystem::create_directories(out / "depth");
  std::filesystem::create_directories(out / "color");
  const test::TestCamera camera{160, 120, 130.0};
  const test::StereoNoise noise = test::stereoNoiseFor(camera, 0.15);
  const auto poses = test::surveyPoses(5, 0.12);
  std::ofstream traj(out / "traj.txt");
  traj << "# timestamp tx ty tz qx qy qz qw\n";
  traj.precision(9);
  for (int i = 0; i < 5; ++i) {
    char stamp[32];
    std::snprintf(stamp, sizeof(stamp), "%.6f", 100.0 + 0.5 * i);
    pipeline::DepthFrame frame = test::renderScene(test::boxScene(), camera, poses[i], 100.0 + 0.5 * i);
    const test::NoisyDepth noisy = test::addStereoNoise(frame.depth, noise, 7 + i);
    io::writePfm((out / "depth" / (std::string(stamp) + ".depth.pfm")).string(), noisy.depth);
    io::writePfm((out / "depth" / (std::string(stamp) + ".conf.pfm")).string(), noisy.confidence);
    io::writeImage((out / "color" / (std::string(stamp) + ".png")).string(), frame.color);
    const Eigen::Quaterniond q(poses[i].linear());
    const Eigen::Vector3d t = poses[i].translation();
    traj << stamp << " " << t.x() << " " << t.y() << " " << t.z() << " " << q.x() << " " << q.y() << " " << q.z() << " "
         << q.w() << "\n";
  }
  const Eigen::Matrix3d K = camera.K();
  std::printf("%g,%g,%g,%g\n", K(0, 0), K(1, 1), K(0, 2), K(1, 2));
  return 0;
}
