#include "pipeline/sim/image_formation.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <vector>

#include "common/error.h"

namespace cenote::pipeline {
namespace {

constexpr float kMinCosine = 0.2f;         // footprint of grazing views is capped at 5x
constexpr int kGammaLevels = 4096;

// exp(x) for x <= 0 to ~2e-4 relative: 2^(x log2 e) split into integer and fraction.
inline float fastExp(float x) {
  x = std::max(x, -80.0f);
  const float t = x * 1.44269504f;
  const float fi = std::floor(t);
  const float f = t - fi;
  const float p = 1.0f + f * (0.6931472f + f * (0.2402265f + f * (0.05550411f + f * (0.009618129f + f * 0.001333355f))));
  const int32_t bits = (static_cast<int32_t>(fi) + 127) << 23;
  float scale;
  std::memcpy(&scale, &bits, sizeof(scale));
  return p * scale;
}

inline Eigen::Array3f expArray(const Eigen::Array3f& x) { return {fastExp(x[0]), fastExp(x[1]), fastExp(x[2])}; }

}  // namespace

SurfaceTexture::SurfaceTexture(uint64_t seed) : fine(kFineSize, hash64(seed, 1)), coarse(kCoarseSize, hash64(seed, 2)) {}

Eigen::Array3f surfaceAlbedo(const SimScene& scene, const SurfaceTexture& texture, const Eigen::Vector3f& p,
                             int triangle, float footprint_m) {
  const Eigen::Vector3f& n = scene.mesh.normals[triangle];
  // Planar projection along the normal's dominant axis (fixed per triangle: view-independent).
  const Eigen::Vector3f a = n.cwiseAbs();
  float u, v;
  if (a.z() >= a.x() && a.z() >= a.y()) {
    u = p.x();
    v = p.y();
  } else if (a.x() >= a.y()) {
    u = p.y();
    v = p.z();
  } else {
    u = p.x();
    v = p.z();
  }
  constexpr auto kFine = static_cast<float>(1.0 / SurfaceTexture::kFineTexel_m);
  constexpr auto kCoarse = static_cast<float>(1.0 / SurfaceTexture::kCoarseTexel_m);
  const float fine = texture.fine.sample(u * kFine, v * kFine, footprint_m * kFine);
  const float coarse = texture.coarse.sample(u * kCoarse + 37.1f, v * kCoarse + 91.7f, footprint_m * kCoarse);
  const float value = std::clamp(0.5f + 1.4f * (0.55f * fine + 0.45f * coarse - 0.5f), 0.0f, 1.0f);
  return scene.albedo[static_cast<size_t>(scene.mesh.materials[triangle])] * (0.15f + 0.85f * value);
}

cv::Mat renderRadiance(const SimScene& scene, const SurfaceTexture& texture, const PinholeCamera& cam,
                       const Eigen::Isometry3d& T_world_cam, const VisibilityBuffer& vis,
                       const Eigen::Isometry3d& T_world_light) {
  const SceneLighting& light = scene.lighting;
  cv::Mat out(cam.height, cam.width, CV_32FC3);
  const Eigen::Matrix3f R = T_world_cam.linear().cast<float>();
  const Eigen::Vector3d origin = T_world_cam.translation();
  const Eigen::Vector3d lamp_world = T_world_light * light.light_in_cam0;
  const Eigen::Vector3d lamp_axis = T_world_light.linear().col(2);
  const Eigen::Array3f beta = light.attenuation_per_m;
  const auto fx = static_cast<float>(cam.fx), fy = static_cast<float>(cam.fy);
  const auto cx = static_cast<float>(cam.cx), cy = static_cast<float>(cam.cy);
  std::vector<float> ray_x(static_cast<size_t>(cam.width));  // x / z of each column's ray
  for (int x = 0; x < cam.width; ++x) ray_x[x] = (x - cx) / fx;
#pragma omp parallel for schedule(static)
  for (int y = 0; y < cam.height; ++y) {
    const float ray_y = (y - cy) / fy;
    const int32_t* ids = vis.triangle.ptr<int32_t>(y);
    const float* depth = vis.depth.ptr<float>(y);
    auto* row = out.ptr<cv::Vec3f>(y);
    for (int x = 0; x < cam.width; ++x) {
      if (ids[x] < 0) {
        row[x] = cv::Vec3f(light.backscatter[0], light.backscatter[1], light.backscatter[2]);
        continue;
      }
      const float z = depth[x];
      const Eigen::Vector3f ray_cam(ray_x[x] * z, ray_y * z, z);
      const float range = ray_cam.norm();
      const Eigen::Vector3f offset_world = R * ray_cam;  // from the camera centre to the point
      // World position relative to the camera, then absolute in double (keeps float precision local).
      const Eigen::Vector3d p_world = origin + offset_world.cast<double>();
      const Eigen::Vector3f view = offset_world / range;
      Eigen::Vector3f n = scene.mesh.normals[ids[x]];
      if (n.dot(view) > 0) n = -n;
      const float cos_view = std::max(kMinCosine, -n.dot(view));
      const float footprint_m = z / fx / cos_view;
      const Eigen::Array3f albedo = surfaceAlbedo(scene, texture, p_world.cast<float>(), ids[x], footprint_m);
      Eigen::Array3f irradiance = Eigen::Array3f::Zero();
      if (light.rig_light) {
        const Eigen::Vector3f to_lamp = (lamp_world - p_world).cast<float>();
        const float d = to_lamp.norm();
        const Eigen::Vector3f l = to_lamp / d;
        const float incidence = std::max(0.0f, n.dot(l));
        const float axis_cos = std::max(0.0f, -l.dot(lamp_axis.cast<float>()));
        const float spot = axis_cos * axis_cos;
        irradiance += light.rig_intensity * spot * incidence / (d * d) * expArray(-beta * d);
      }
      if (light.sun) {
        const float below = std::max(0.0f, light.surface_z_m - static_cast<float>(p_world.z()));
        const float facing = light.ambient + (1.0f - light.ambient) * std::max(0.0f, n.z());
        irradiance += light.sun_irradiance * expArray(-light.downwelling_per_m * below) * facing;
      }
      const Eigen::Array3f transmission = expArray(-beta * range);
      const Eigen::Array3f radiance = albedo * irradiance * transmission + light.backscatter * (1.0f - transmission);
      row[x] = cv::Vec3f(radiance[0], radiance[1], radiance[2]);
    }
  }
  return out;
}

cv::Mat exposeImage(const cv::Mat& radiance, float gain, float noise_sigma, uint64_t noise_seed) {
  if (radiance.type() != CV_32FC3) throw Error("exposeImage: radiance must be CV_32FC3");
  static const std::vector<float> gamma = [] {
    std::vector<float> table(kGammaLevels + 1);
    for (int i = 0; i <= kGammaLevels; ++i) table[i] = 255.0f * std::pow(static_cast<float>(i) / kGammaLevels, 1.0f / 2.2f);
    return table;
  }();
  cv::Mat out(radiance.size(), CV_8UC3);
  const int width = radiance.cols;
#pragma omp parallel for schedule(static)
  for (int y = 0; y < radiance.rows; ++y) {
    const auto* in = radiance.ptr<float>(y);
    uint8_t* o = out.ptr<uint8_t>(y);
    for (int i = 0; i < 3 * width; ++i) {
      const float v = std::clamp(in[i] * gain, 0.0f, 1.0f);
      const float level = gamma[static_cast<int>(v * kGammaLevels + 0.5f)];
      const uint64_t index = static_cast<uint64_t>(y) * 3 * width + i;
      const float noisy = level + noise_sigma * approxGaussian(hash64(noise_seed, index));
      o[i] = static_cast<uint8_t>(std::clamp(noisy + 0.5f, 0.0f, 255.0f));
    }
  }
  return out;
}

float autoExposureGain(const cv::Mat& radiance, const VisibilityBuffer& vis, double percentile, float target) {
  std::vector<float> values;
  for (int y = 0; y < radiance.rows; y += 2) {
    const auto* row = radiance.ptr<cv::Vec3f>(y);
    const int32_t* ids = vis.triangle.ptr<int32_t>(y);
    for (int x = 0; x < radiance.cols; x += 2) {
      if (ids[x] >= 0) values.push_back(std::max({row[x][0], row[x][1], row[x][2]}));
    }
  }
  if (values.empty()) return 1.0f;
  const size_t k = std::min(values.size() - 1, static_cast<size_t>(percentile / 100.0 * values.size()));
  std::nth_element(values.begin(), values.begin() + static_cast<long>(k), values.end());
  return values[k] > 0 ? target / values[k] : 1.0f;
}

}  // namespace cenote::pipeline
