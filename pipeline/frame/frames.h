// frames.h: the plain value types handed from stage to stage of the pipeline.
//   StereoFrame -> (frame admission) -> PosedPair{RectifiedPair} -> DisparityMap -> DepthFrame
// Units: seconds, metres, pixels. Frames: T_world_cam maps camera points to the world.
// Images are row-major cv::Mat; a Mat header shares pixels, so a stage that keeps a frame while
// the producer goes on must clone() what it keeps.
#pragma once

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

namespace cenote::pipeline {

// Pinhole model of the rectified left camera and the stereo baseline.
struct StereoGeometry {
  double fx = 0.0, fy = 0.0, cx = 0.0, cy = 0.0;  // pixels
  double baseline_m = 0.0;                        // distance between the optical centres
  cv::Size image_size;

  Eigen::Matrix3d K() const {
    Eigen::Matrix3d k;
    k << fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0;
    return k;
  }
};

// A raw pair as it came from the cameras.
struct StereoFrame {
  double t_s = 0.0;
  cv::Mat left, right;  // 8-bit, grey or BGR
};

// A pair whose rows correspond: a point at (x, y) in the left image is at (x - d, y) in the right.
struct RectifiedPair {
  double t_s = 0.0;
  cv::Mat left, right;  // 8-bit, grey or BGR, same size
  StereoGeometry geometry;
};

// Output of the matcher, in the left image.
struct DisparityMap {
  cv::Mat disparity;   // CV_32F pixels; +inf where invalid (never 0)
  cv::Mat confidence;  // CV_32F PKRN ratio >= 1; 0 where invalid
};

// A rectified pair with the pose of its rectified left camera: what frame admission
// (frame_admission.h) hands to the stereo stage.
struct PosedPair {
  RectifiedPair pair;
  Eigen::Isometry3d T_world_cam = Eigen::Isometry3d::Identity();
};

// Depth of the left view with everything the later stages need: the stereo stage's output and
// the fusion window's input and output, inside the pipeline. It is cv::Mat based (OpenCV does the
// pipeline's image work, and a Mat header shares pixels between stages without copies) and carries
// the PKRN confidence that fusion weighs. The map never sees it: the pipeline hands the map
// PointBatch (common/point_batch.h), and the map's own depth-image input for projective
// integration, mapping/integration/depth_frame.h, is OpenCV-free because mapping/ does not link
// OpenCV. Two types on purpose, one per side of that boundary.
struct DepthFrame {
  double t_s = 0.0;
  cv::Mat depth;       // CV_32F metres along the optical axis; +inf where none
  cv::Mat confidence;  // CV_32F; 0 where no depth
  cv::Mat color;       // CV_8UC3 BGR left image (may be empty)
  Eigen::Matrix3d K = Eigen::Matrix3d::Identity();
  Eigen::Isometry3d T_world_cam = Eigen::Isometry3d::Identity();
};

}  // namespace cenote::pipeline
