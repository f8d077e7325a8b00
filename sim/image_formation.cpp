#include "sim/image_formation.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <vector>

#include "common/error.h"
#include "sim/image_formation_kernels.h"

namespace cenote::sim {
namespace {

constexpr int kGammaLevels = 4096;

}  // namespace

SurfaceTexture::SurfaceTexture(uint64_t seed) : fine(kFineSize, hash64(seed, 1)), coarse(kCoarseSize, hash64(seed, 2)) {}

Eigen::Array3f surfaceAlbedo(const SimScene& scene, const SurfaceTexture& texture, const Eigen::Vector3f& p, int triangle,
                             float footprint_m) {
  float u, v;
  switch (static_cast<TexturePlane>(scene.mesh.shading_codes[triangle] & 3)) {
    case TexturePlane::kXY: u = p.x(), v = p.y(); break;
    case TexturePlane::kYZ: u = p.y(), v = p.z(); break;
    default: u = p.x(), v = p.z(); break;
  }
  constexpr auto kFine = static_cast<float>(1.0 / SurfaceTexture::kFineTexel_m);
  constexpr auto kCoarse = static_cast<float>(1.0 / SurfaceTexture::kCoarseTexel_m);
  const float fine = texture.fine.sample(u * kFine, v * kFine, footprint_m * kFine);
  const float coarse = texture.coarse.sample(u * kCoarse + SurfaceTexture::kCoarseShiftU,
                                             v * kCoarse + SurfaceTexture::kCoarseShiftV, footprint_m * kCoarse);
  using T = SurfaceTexture;
  const float mix = T::kFineWeight * fine + (1.0f - T::kFineWeight) * coarse;
  const float value = std::clamp(0.5f + T::kContrast * (mix - 0.5f), 0.0f, 1.0f);
  return scene.albedo[static_cast<size_t>(scene.mesh.materials[triangle])] * (T::kMinShade + (1.0f - T::kMinShade) * value);
}

namespace {

// The texture layer as the shader reads it, with the camera centre's coordinates in each plane.
detail::TextureLayer textureLayer(const NoiseTexture& texture, double texel_m, float shift_u, float shift_v,
                                  const Eigen::Vector3d& camera_world) {
  detail::TextureLayer layer;
  layer.quads = texture.quads();
  layer.level_offsets = texture.levelOffsets();
  layer.size_log2 = texture.sizeLog2();
  layer.levels = texture.levels();
  layer.texels_per_m = static_cast<float>(1.0 / texel_m);
  const double period = texture.size();
  auto wrap = [&](double texels) {
    const auto w = static_cast<float>(texels - period * std::floor(texels / period));
    return w < period ? w : 0.0f;
  };
  const Eigen::Vector3d c = camera_world * static_cast<double>(layer.texels_per_m);
  const double u[3] = {c.x(), c.y(), c.x()}, v[3] = {c.y(), c.z(), c.z()};  // TexturePlane order
  for (int plane = 0; plane < 3; ++plane) {
    layer.origin_u[plane] = wrap(u[plane] + shift_u);
    layer.origin_v[plane] = wrap(v[plane] + shift_v);
  }
  return layer;
}

// What the shader needs for one camera image.
detail::RadianceSetup radianceSetup(const SimScene& scene, const SurfaceTexture& texture, const PinholeCamera& cam,
                                    const Eigen::Isometry3d& T_world_cam, const Eigen::Isometry3d& T_world_light) {
  const SceneLighting& light = scene.lighting;
  const Eigen::Vector3d origin = T_world_cam.translation();
  detail::RadianceSetup s;
  s.width = cam.width;
  s.fx = static_cast<float>(cam.fx);
  s.fy = static_cast<float>(cam.fy);
  s.cx = static_cast<float>(cam.cx);
  s.cy = static_cast<float>(cam.cy);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) s.R[3 * r + c] = static_cast<float>(T_world_cam.linear()(r, c));
  }
  s.normals = scene.mesh.normals.front().data();
  s.shading_codes = scene.mesh.shading_codes.data();
  for (size_t m = 0; m < scene.albedo.size(); ++m) {
    for (int c = 0; c < 3; ++c) s.albedo[c][m] = scene.albedo[m][c];
  }
  s.fine = textureLayer(texture.fine, SurfaceTexture::kFineTexel_m, 0.0f, 0.0f, origin);
  s.coarse = textureLayer(texture.coarse, SurfaceTexture::kCoarseTexel_m, SurfaceTexture::kCoarseShiftU,
                          SurfaceTexture::kCoarseShiftV, origin);
  const Eigen::Vector3d lamp = T_world_light * light.light_in_cam0 - origin;
  const Eigen::Vector3d lamp_axis = T_world_light.linear().col(2);
  for (int c = 0; c < 3; ++c) {
    s.beta[c] = light.attenuation_per_m[c];
    s.backscatter[c] = light.backscatter[c];
    s.sun_irradiance[c] = light.sun_irradiance[c];
    s.downwelling[c] = light.downwelling_per_m[c];
    s.lamp[c] = static_cast<float>(lamp[c]);
    s.lamp_axis[c] = static_cast<float>(lamp_axis[c]);
  }
  s.rig_light = light.rig_light;
  s.rig_intensity = light.rig_intensity;
  s.sun = light.sun;
  s.surface_above_camera_m = static_cast<float>(light.surface_z_m - origin.z());
  s.ambient = light.ambient;

  return s;
}

const std::vector<float>& gammaTable() {
  static const std::vector<float> table = [] {
    std::vector<float> t(kGammaLevels + 1);
    for (int i = 0; i <= kGammaLevels; ++i) t[i] = 255.0f * std::pow(static_cast<float>(i) / kGammaLevels, 1.0f / 2.2f);
    return t;
  }();
  return table;
}

}  // namespace

cv::Mat renderRadiance(const SimScene& scene, const SurfaceTexture& texture, const PinholeCamera& cam,
                       const Eigen::Isometry3d& T_world_cam, const VisibilityBuffer& vis,
                       const Eigen::Isometry3d& T_world_light) {
  const detail::RadianceSetup s = radianceSetup(scene, texture, cam, T_world_cam, T_world_light);
  cv::Mat out(cam.height, cam.width, CV_32FC3);
#pragma omp parallel for schedule(static)
  for (int y = 0; y < cam.height; ++y) {
    detail::shadeRadianceRow(s, y, vis.triangle.ptr<int32_t>(y), vis.depth.ptr<float>(y), out.ptr<float>(y));
  }
  return out;
}

cv::Mat renderImage(const SimScene& scene, const SurfaceTexture& texture, const PinholeCamera& cam,
                    const Eigen::Isometry3d& T_world_cam, const VisibilityBuffer& vis,
                    const Eigen::Isometry3d& T_world_light, float gain, float noise_sigma, uint64_t noise_seed) {
  const detail::RadianceSetup s = radianceSetup(scene, texture, cam, T_world_cam, T_world_light);
  const std::vector<float>& gamma = gammaTable();
  cv::Mat out(cam.height, cam.width, CV_8UC3);
  const int samples = 3 * cam.width;
#pragma omp parallel
  {
    std::vector<float> radiance(static_cast<size_t>(samples));  // one row, stays in cache
#pragma omp for schedule(static)
    for (int y = 0; y < cam.height; ++y) {
      detail::shadeRadianceRow(s, y, vis.triangle.ptr<int32_t>(y), vis.depth.ptr<float>(y), radiance.data());
      detail::exposeRow(radiance.data(), samples, static_cast<uint32_t>(y) * static_cast<uint32_t>(samples), gain,
                        noise_sigma, noise_seed, gamma.data(), kGammaLevels, out.ptr<uint8_t>(y));
    }
  }
  return out;
}

cv::Mat exposeImage(const cv::Mat& radiance, float gain, float noise_sigma, uint64_t noise_seed) {
  if (radiance.type() != CV_32FC3) throw Error("exposeImage: radiance must be CV_32FC3");
  const std::vector<float>& gamma = gammaTable();
  cv::Mat out(radiance.size(), CV_8UC3);
  const int samples = 3 * radiance.cols;
#pragma omp parallel for schedule(static)
  for (int y = 0; y < radiance.rows; ++y) {
    detail::exposeRow(radiance.ptr<float>(y), samples, static_cast<uint32_t>(y) * static_cast<uint32_t>(samples), gain,
                      noise_sigma, noise_seed, gamma.data(), kGammaLevels, out.ptr<uint8_t>(y));
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

}  // namespace cenote::sim
