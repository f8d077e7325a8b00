#include "tests/support/plane_sequence.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace cenote::test {
namespace fs = std::filesystem;
namespace {

// Smooth texture of the plane, in world metres: a fixed random image of 1 cm texels over 8 x 6 m,
// blurred so that the cameras (about 7 mm a pixel at 2 m) sample it without aliasing.
class PlaneTexture {
 public:
  PlaneTexture() : image_(600, 800, CV_32F) {
    cv::RNG rng(17);
    rng.fill(image_, cv::RNG::UNIFORM, 0.0, 255.0);
    cv::GaussianBlur(image_, image_, cv::Size(0, 0), 2.0);
    cv::normalize(image_, image_, 30, 225, cv::NORM_MINMAX);
  }
  // Bilinear sample at world (x, y).
  float at(double x_m, double y_m) const {
    const double u = x_m / 0.01 + 400.0, v = y_m / 0.01 + 300.0;
    const int x0 = static_cast<int>(std::floor(u)), y0 = static_cast<int>(std::floor(v));
    const double fx = u - x0, fy = v - y0;
    auto px = [&](int x, int y) {
      return image_.at<float>(std::clamp(y, 0, image_.rows - 1), std::clamp(x, 0, image_.cols - 1));
    };
    return static_cast<float>((1 - fy) * ((1 - fx) * px(x0, y0) + fx * px(x0 + 1, y0)) +
                              fy * ((1 - fx) * px(x0, y0 + 1) + fx * px(x0 + 1, y0 + 1)));
  }

 private:
  cv::Mat image_;
};

// The image of a camera at world x = cam_x (looking along +z, no rotation).
cv::Mat render(const PlaneTexture& texture, const PlaneSequence& s, double cam_x) {
  cv::Mat image(s.height, s.width, CV_8U);
  const double cx = s.width / 2.0, cy = s.height / 2.0;
  for (int v = 0; v < s.height; ++v)
    for (int u = 0; u < s.width; ++u) {
      const double x = (u - cx) * s.depth_m / s.fx + cam_x, y = (v - cy) * s.depth_m / s.fx;
      image.at<uint8_t>(v, u) = cv::saturate_cast<uint8_t>(texture.at(x, y));
    }
  return image;
}

double cameraX(const PlaneSequence& s, double t_s) { return s.speed_m_s * (t_s - s.t0_s); }

void writeSensor(const fs::path& path, const PlaneSequence& s, double x_in_body) {
  std::ofstream out(path);
  out << "%YAML:1.0\nsensor_type: camera\ncomment: plane sequence\nT_BS:\n  cols: 4\n  rows: 4\n"
      << "  data: [1.0, 0.0, 0.0, " << x_in_body << ", 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0]\n"
      << "rate_hz: " << s.rate_hz << "\nresolution: [" << s.width << ", " << s.height << "]\ncamera_model: pinhole\n"
      << "intrinsics: [" << s.fx << ", " << s.fx << ", " << s.width / 2.0 << ", " << s.height / 2.0 << "]\n"
      << "distortion_model: radial-tangential\ndistortion_coefficients: [0.0, 0.0, 0.0, 0.0]\n";
}

}  // namespace

void writeEurocPlaneSequence(const std::string& dir, const PlaneSequence& s) {
  const PlaneTexture texture;
  const fs::path mav0 = fs::path(dir) / "mav0";
  for (const char* cam : {"cam0", "cam1"}) fs::create_directories(mav0 / cam / "data");
  fs::create_directories(mav0 / "state_groundtruth_estimate0");
  std::ofstream csv0(mav0 / "cam0" / "data.csv"), csv1(mav0 / "cam1" / "data.csv");
  csv0 << "#timestamp [ns],filename\n";
  csv1 << "#timestamp [ns],filename\n";
  for (int i = 0; i < s.frames; ++i) {
    const double t = s.t0_s + i / s.rate_hz;
    const long long ns = std::llround(t * 1e9);
    const std::string name = std::to_string(ns) + ".png";
    cv::imwrite((mav0 / "cam0" / "data" / name).string(), render(texture, s, cameraX(s, t)));
    cv::imwrite((mav0 / "cam1" / "data" / name).string(), render(texture, s, cameraX(s, t) + s.baseline_m));
    csv0 << ns << "," << name << "\n";
    csv1 << ns << "," << name << "\n";
  }
  writeSensor(mav0 / "cam0" / "sensor.yaml", s, s.body_offset_x_m);
  writeSensor(mav0 / "cam1" / "sensor.yaml", s, s.body_offset_x_m + s.baseline_m);
  // Body poses: the camera is at body + offset, so the body is at cameraX - offset.
  std::ofstream gt(mav0 / "state_groundtruth_estimate0" / "data.csv");
  gt << "#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], q_RS_z []\n";
  gt.precision(12);
  const double end = s.t0_s + (s.frames - 1) / s.rate_hz + 0.01;
  for (double t = s.t0_s - 0.01; t <= end; t += 0.005) {
    gt << std::llround(t * 1e9) << "," << cameraX(s, t) - s.body_offset_x_m << ",0,0,1,0,0,0\n";
  }
}

void writeKittiPlaneSequence(const std::string& dir, const PlaneSequence& s) {
  const PlaneTexture texture;
  const fs::path seq = fs::path(dir) / "sequences" / "00";
  fs::create_directories(seq / "image_0");
  fs::create_directories(seq / "image_1");
  fs::create_directories(fs::path(dir) / "poses");
  std::ofstream times(seq / "times.txt"), poses(fs::path(dir) / "poses" / "00.txt");
  poses.precision(12);
  for (int i = 0; i < s.frames; ++i) {
    const double t = i / s.rate_hz;
    char name[32];
    std::snprintf(name, sizeof(name), "%06d.png", i);
    cv::imwrite((seq / "image_0" / name).string(), render(texture, s, s.speed_m_s * t));
    cv::imwrite((seq / "image_1" / name).string(), render(texture, s, s.speed_m_s * t + s.baseline_m));
    times << t << "\n";
    poses << "1 0 0 " << s.speed_m_s * t << " 0 1 0 0 0 0 1 0\n";
  }
  std::ofstream calib(seq / "calib.txt");
  const double cx = s.width / 2.0, cy = s.height / 2.0;
  calib << "P0: " << s.fx << " 0 " << cx << " 0 0 " << s.fx << " " << cy << " 0 0 0 1 0\n";
  calib << "P1: " << s.fx << " 0 " << cx << " " << -s.fx * s.baseline_m << " 0 " << s.fx << " " << cy << " 0 0 0 1 0\n";
}

}  // namespace cenote::test
