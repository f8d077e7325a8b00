// Image formation: the SIMD shader (renderRadiance) against the model as sim_scene.h writes it,
// evaluated per pixel in double with the scalar surfaceAlbedo; and the model's effects that the
// images must show (attenuation with range, backscatter, light fall-off).
#include "sim/image_formation.h"

#include <gtest/gtest.h>

#include <cmath>

#include "sim/image_formation_kernels.h"
#include "sim/simulator.h"

namespace cenote::sim {
namespace {

// J_c = rho_c E_c exp(-beta_c r) + B_c (1 - exp(-beta_c r)) at pixel (x, y), straight from the
// formulas of SceneLighting; the texture from surfaceAlbedo.
Eigen::Array3d referenceRadiance(const Simulator& sim, const Eigen::Isometry3d& T_world_cam, const VisibilityBuffer& vis,
                                 int x, int y) {
  const SimScene& scene = sim.scene();
  const SceneLighting& light = scene.lighting;
  const Eigen::Array3d beta = light.attenuation_per_m.cast<double>();
  const Eigen::Array3d backscatter = light.backscatter.cast<double>();
  const int32_t t = vis.triangle.at<int32_t>(y, x);
  if (t < 0) return backscatter;
  const PinholeCamera& cam = sim.rig().camera;
  const double z = vis.depth.at<float>(y, x);
  const Eigen::Vector3d p_cam((x - cam.cx) / cam.fx * z, (y - cam.cy) / cam.fy * z, z);
  const Eigen::Vector3d p_world = T_world_cam * p_cam;
  const double range = p_cam.norm();
  const Eigen::Vector3d view = (p_world - T_world_cam.translation()) / range;
  Eigen::Vector3d n = scene.mesh.normals[t].cast<double>();
  if (n.dot(view) > 0) n = -n;
  const double footprint_m = z / cam.fx / std::max(0.2, -n.dot(view));
  const Eigen::Array3d albedo =
      surfaceAlbedo(scene, sim.texture(), p_world.cast<float>(), t, static_cast<float>(footprint_m)).cast<double>();
  Eigen::Array3d irradiance = Eigen::Array3d::Zero();
  if (light.rig_light) {
    const Eigen::Vector3d to_lamp = T_world_cam * light.light_in_cam0 - p_world;  // the rig is cam0
    const double d = to_lamp.norm();
    const Eigen::Vector3d l = to_lamp / d;
    const double axis_cos = std::max(0.0, -l.dot(T_world_cam.linear().col(2)));
    irradiance += light.rig_intensity * axis_cos * axis_cos * std::max(0.0, n.dot(l)) / (d * d) * (-beta * d).exp();
  }
  if (light.sun) {
    const double below = std::max(0.0, light.surface_z_m - p_world.z());
    const double facing = light.ambient + (1.0 - light.ambient) * std::max(0.0, n.z());
    irradiance += light.sun_irradiance.cast<double>() * (-light.downwelling_per_m.cast<double>() * below).exp() * facing;
  }
  const Eigen::Array3d transmission = (-beta * range).exp();
  return albedo * irradiance * transmission + backscatter * (1.0 - transmission);
}

class ImageFormation : public ::testing::TestWithParam<SimSceneKind> {};

TEST_P(ImageFormation, RadianceMatchesTheModelPerPixel) {
  SimConfig config;
  config.scene = GetParam();
  config.num_frames = 4;
  config.width_px = 203;  // not a multiple of any vector width: the row tail is shaded too
  config.height_px = 150;
  config.hfov_deg = 80.0;
  const Simulator sim(config);
  const Eigen::Isometry3d T = sim.T_world_cam0(sim.frameTimeS(2));
  const VisibilityBuffer vis = rasterize(sim.scene().mesh, sim.rig().camera, T);
  const cv::Mat radiance = renderRadiance(sim.scene(), sim.texture(), sim.rig().camera, T, vis, T);
  int surface = 0, checked = 0;
  double worst = 0.0;
  for (int y = 0; y < vis.triangle.rows; ++y) {
    for (int x = 0; x < vis.triangle.cols; ++x) {
      const Eigen::Array3d expected = referenceRadiance(sim, T, vis, x, y);
      const cv::Vec3f got = radiance.at<cv::Vec3f>(y, x);
      for (int c = 0; c < 3; ++c) {
        // 0.2 % of the value: float and the polynomial exp/log2, and texture coordinates taken
        // relative to the camera (a hair apart from the absolute ones of surfaceAlbedo).
        const double error = std::abs(got[c] - expected[c]) / (std::abs(expected[c]) + 1e-3);
        worst = std::max(worst, error);
        EXPECT_LT(error, 2e-3) << "pixel (" << x << ", " << y << ") channel " << c << ": " << got[c] << " vs "
                               << expected[c];
        if (error >= 2e-3) return;  // one report, not thousands
      }
      surface += vis.triangle.at<int32_t>(y, x) >= 0;
      ++checked;
    }
  }
  EXPECT_GT(surface, checked / 2);
  std::printf("[ image formation ] %s: worst relative error %.2g over %d pixels\n", toString(GetParam()), worst, checked);
}

TEST(Exposure, RenderImageIsExposeImageOfRenderRadiance) {
  SimConfig config;
  config.scene = SimSceneKind::kReef;
  config.num_frames = 2;
  config.width_px = 203;
  config.height_px = 150;
  const Simulator sim(config);
  const Eigen::Isometry3d T = sim.T_world_cam0(0.0);
  const VisibilityBuffer vis = rasterize(sim.scene().mesh, sim.rig().camera, T);
  const cv::Mat radiance = renderRadiance(sim.scene(), sim.texture(), sim.rig().camera, T, vis, T);
  const cv::Mat a = exposeImage(radiance, 1.3f, 2.0f, 77);
  const cv::Mat b = renderImage(sim.scene(), sim.texture(), sim.rig().camera, T, vis, T, 1.3f, 2.0f, 77);
  ASSERT_EQ(a.size(), cv::Size(203, 150));  // two empty images would compare equal too
  ASSERT_GT(cv::countNonZero(a.reshape(1)), a.rows * a.cols / 2) << "mostly black image";
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0);
}

TEST(Exposure, NoiseIsTheSensorNoiseWithTheConfiguredSigma) {
  const cv::Mat radiance(64, 101, CV_32FC3, cv::Scalar::all(0.25));
  constexpr float kSigma = 5.0f;
  constexpr uint64_t kKey = 0x0123456789ABCDEFULL;
  const cv::Mat image = exposeImage(radiance, 1.0f, kSigma, kKey);
  const double level = 255.0 * std::pow(0.25, 1.0 / 2.2);
  double sum = 0.0, square = 0.0;
  int exact = 0;
  const int samples = 3 * radiance.cols * radiance.rows;
  for (int k = 0; k < samples; ++k) {
    const int got = image.data[k];
    const double noisy = level + kSigma * detail::sensorNoise(kKey, static_cast<uint32_t>(k));
    const long expected = std::lround(std::clamp(noisy, 0.0, 255.0));
    ASSERT_LE(std::abs(got - expected), 1) << "sample " << k;  // 1: rounding of x.5 with a fused multiply-add
    exact += got == expected;
    sum += got - level;
    square += (got - level) * (got - level);
  }
  EXPECT_GT(exact, 0.99 * samples);
  const double mean = sum / samples, sd = std::sqrt(square / samples - mean * mean);
  EXPECT_NEAR(mean, 0.0, 0.1);
  EXPECT_NEAR(sd, std::sqrt(kSigma * kSigma + 1.0 / 12.0), 0.1);  // noise and 8-bit rounding
}

INSTANTIATE_TEST_SUITE_P(Scenes, ImageFormation,
                         ::testing::Values(SimSceneKind::kCave, SimSceneKind::kReef, SimSceneKind::kWreck),
                         [](const auto& info) { return std::string(toString(info.param)); });

}  // namespace
}  // namespace cenote::sim
