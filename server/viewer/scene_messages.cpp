#include "server/viewer/scene_messages.h"

#include <charconv>
#include <cmath>
#include <cstring>
#include <nlohmann/json.hpp>

#include "mapping/frontier/frontier_map.h"

namespace cenote::server::viewer {
namespace {

using nlohmann::json;

void appendNumber(std::string& out, double value, int decimals) {
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value, std::chars_format::fixed, decimals);
  char* end = result.ptr;
  // "1.2500" -> "1.25", "2.000" -> "2": the JSON is shorter and means the same.
  if (std::memchr(buffer, '.', end - buffer) != nullptr) {
    while (end[-1] == '0') --end;
    if (end[-1] == '.') --end;
  }
  if (end - buffer == 2 && buffer[0] == '-' && buffer[1] == '0') {
    out += '0';
    return;
  }
  out.append(buffer, end);
}

std::string stampOf(uint64_t time_ns) {
  return "{\"sec\":" + std::to_string(time_ns / 1000000000ull) + ",\"nsec\":" + std::to_string(time_ns % 1000000000ull) +
         "}";
}

json stampJson(uint64_t time_ns) { return {{"sec", time_ns / 1000000000ull}, {"nsec", time_ns % 1000000000ull}}; }

json vectorJson(const Eigen::Vector3d& v) { return {{"x", v.x()}, {"y", v.y()}, {"z", v.z()}}; }
json quaternionJson(const Eigen::Quaterniond& q) { return {{"x", q.x()}, {"y", q.y()}, {"z", q.z()}, {"w", q.w()}}; }
json poseJson(const Eigen::Vector3d& p, const Eigen::Quaterniond& q) {
  return {{"position", vectorJson(p)}, {"orientation", quaternionJson(q)}};
}
json colorJson(double r, double g, double b, double a) { return {{"r", r}, {"g", g}, {"b", b}, {"a", a}}; }

std::string base64(const uint8_t* data, size_t size) {
  static const char* kAlphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((size + 2) / 3 * 4);
  size_t i = 0;
  for (; i + 2 < size; i += 3) {
    const uint32_t v = (uint32_t{data[i]} << 16) | (uint32_t{data[i + 1]} << 8) | data[i + 2];
    for (int k = 3; k >= 0; --k) out += kAlphabet[(v >> (6 * k)) & 63];
  }
  if (i < size) {
    const uint32_t v = (uint32_t{data[i]} << 16) | (i + 1 < size ? uint32_t{data[i + 1]} << 8 : 0u);
    out += kAlphabet[(v >> 18) & 63];
    out += kAlphabet[(v >> 12) & 63];
    out += i + 1 < size ? kAlphabet[(v >> 6) & 63] : '=';
    out += '=';
  }
  return out;
}

// The fields of an entity after its cubes: the primitives cenote does not use, empty.
constexpr const char* kEntityTail =
    "],\"spheres\":[],\"cylinders\":[],\"lines\":[],\"triangles\":[],\"texts\":[],\"models\":[]}";
constexpr size_t kCubeBytes = 155;  // a cube as blockEntity writes it (6-digit coordinates) and its probability
constexpr size_t kEntityBytes = 330;

}  // namespace

std::array<uint8_t, 3> heightColor(double z_m) {
  constexpr double kPi = 3.14159265358979323846;
  const double phase = 2.0 * kPi * z_m / 4.0;
  auto channel = [&](double shift) { return static_cast<uint8_t>(std::lround(127.5 + 127.5 * std::cos(phase + shift))); };
  return {channel(0.0), channel(2.0 * kPi / 3.0), channel(4.0 * kPi / 3.0)};
}

std::string blockEntityId(const mapping::BlockIndex& block) {
  return "block/" + std::to_string(block.x()) + "/" + std::to_string(block.y()) + "/" + std::to_string(block.z());
}

SceneUpdateWriter::SceneUpdateWriter(uint64_t time_ns, std::string frame_id)
    : stamp_(stampOf(time_ns)), frame_id_(std::move(frame_id)) {}

void SceneUpdateWriter::deleteEntity(const std::string& id) {
  if (!deletions_.empty()) deletions_ += ',';
  deletions_ += "{\"timestamp\":" + stamp_ + ",\"type\":0,\"id\":\"" + id + "\"}";
}

size_t SceneUpdateWriter::entityBytes(size_t cubes) { return kEntityBytes + cubes * kCubeBytes; }

void SceneUpdateWriter::blockEntity(const mapping::BlockIndex& block, const std::vector<VoxelCube>& cubes, float cube_m,
                                    bool coarse, uint64_t voxels, const std::vector<float>& probabilities) {
  std::string& out = entities_;
  if (!out.empty()) out += ',';
  out += "{\"timestamp\":" + stamp_ + ",\"frame_id\":\"" + frame_id_ + "\",\"id\":\"" + blockEntityId(block) +
         "\",\"lifetime\":{\"sec\":0,\"nsec\":0},\"frame_locked\":false,\"metadata\":[{\"key\":\"lod\",\"value\":\"" +
         (coarse ? "coarse" : "full") + "\"},{\"key\":\"voxels\",\"value\":\"" + std::to_string(voxels) + "\"}";
  if (!probabilities.empty()) {
    out += ",{\"key\":\"probabilities\",\"value\":\"";
    for (size_t i = 0; i < probabilities.size(); ++i) {
      if (i > 0) out += ',';
      appendNumber(out, probabilities[i], 2);
    }
    out += "\"}";
  }
  out += "],\"arrows\":[],\"cubes\":[";
  std::string size;
  appendNumber(size, cube_m, 6);
  const std::string size_json = "},\"orientation\":{\"x\":0,\"y\":0,\"z\":0,\"w\":1}},\"size\":{\"x\":" + size +
                                ",\"y\":" + size + ",\"z\":" + size + "},\"color\":{\"r\":";
  for (size_t i = 0; i < cubes.size(); ++i) {
    const VoxelCube& c = cubes[i];
    out += i == 0 ? "{\"pose\":{\"position\":{\"x\":" : ",{\"pose\":{\"position\":{\"x\":";
    appendNumber(out, c.centre_m.x(), 4);
    out += ",\"y\":";
    appendNumber(out, c.centre_m.y(), 4);
    out += ",\"z\":";
    appendNumber(out, c.centre_m.z(), 4);
    out += size_json;
    appendNumber(out, c.rgb[0] / 255.0, 3);
    out += ",\"g\":";
    appendNumber(out, c.rgb[1] / 255.0, 3);
    out += ",\"b\":";
    appendNumber(out, c.rgb[2] / 255.0, 3);
    out += ",\"a\":1}}";
  }
  out += kEntityTail;
}

std::string SceneUpdateWriter::finish() const {
  return "{\"deletions\":[" + deletions_ + "],\"entities\":[" + entities_ + "]}";
}

std::string frameTransformJson(uint64_t time_ns, const std::string& frame_id, const Eigen::Isometry3d& T_world_cam) {
  return json{{"timestamp", stampJson(time_ns)},
              {"parent_frame_id", frame_id},
              {"child_frame_id", "camera"},
              {"translation", vectorJson(T_world_cam.translation())},
              {"rotation", quaternionJson(Eigen::Quaterniond(T_world_cam.linear()))}}
      .dump();
}

std::string posesInFrameJson(uint64_t time_ns, const std::string& frame_id, const std::vector<Eigen::Isometry3d>& poses) {
  json list = json::array();
  for (const Eigen::Isometry3d& T : poses) list.push_back(poseJson(T.translation(), Eigen::Quaterniond(T.linear())));
  return json{{"timestamp", stampJson(time_ns)}, {"frame_id", frame_id}, {"poses", std::move(list)}}.dump();
}

std::string pointCloudJson(uint64_t time_ns, const std::string& frame_id, const PointBatch& batch) {
  constexpr size_t kStride = 15;
  std::vector<uint8_t> data(batch.size() * kStride);
  for (size_t i = 0; i < batch.size(); ++i) {
    std::memcpy(&data[i * kStride], batch.points[i].data(), 12);
    const std::array<uint8_t, 3> rgb = batch.hasColor() ? batch.colors[i] : heightColor(batch.points[i].z());
    std::memcpy(&data[i * kStride + 12], rgb.data(), 3);
  }
  json fields = json::array();
  const char* names[] = {"x", "y", "z", "red", "green", "blue"};
  for (int f = 0; f < 6; ++f) {
    fields.push_back({{"name", names[f]}, {"offset", f < 3 ? 4 * f : 12 + (f - 3)}, {"type", f < 3 ? 7 : 1}});
  }
  return json{{"timestamp", stampJson(time_ns)},
              {"frame_id", frame_id},
              {"pose", poseJson(Eigen::Vector3d::Zero(), Eigen::Quaterniond::Identity())},
              {"point_stride", kStride},
              {"fields", std::move(fields)},
              {"data", base64(data.data(), data.size())}}
      .dump();
}

std::string compressedImageJson(uint64_t time_ns, const std::string& jpeg) {
  return json{{"timestamp", stampJson(time_ns)},
              {"frame_id", "camera"},
              {"format", "jpeg"},
              {"data", base64(reinterpret_cast<const uint8_t*>(jpeg.data()), jpeg.size())}}
      .dump();
}

std::string frontierSceneJson(uint64_t time_ns, const std::string& frame_id,
                              const std::vector<mapping::FrontierCluster>& clusters) {
  json entities = json::array();
  for (const mapping::FrontierCluster& c : clusters) {
    const Eigen::Vector3d centre = 0.5 * (c.bounds_m.min_m + c.bounds_m.max_m);
    const Eigen::Vector3d size = (c.bounds_m.max_m - c.bounds_m.min_m).cwiseMax(Eigen::Vector3d::Constant(1e-3));
    const Eigen::Vector3d direction = c.direction.norm() > 1e-9 ? c.direction.normalized() : Eigen::Vector3d::UnitX();
    const Eigen::Quaterniond along = Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitX(), direction);
    const double length = std::max(0.1, 0.5 * size.maxCoeff());
    entities.push_back({{"timestamp", stampJson(time_ns)},
                        {"frame_id", frame_id},
                        {"id", "frontier/" + std::to_string(c.id)},
                        {"lifetime", {{"sec", 0}, {"nsec", 0}}},
                        {"frame_locked", false},
                        {"metadata", json::array({{{"key", "voxels"}, {"value", std::to_string(c.num_voxels)}}})},
                        {"arrows", json::array({{{"pose", poseJson(c.centroid_m, along)},
                                                 {"shaft_length", 0.7 * length},
                                                 {"shaft_diameter", 0.02},
                                                 {"head_length", 0.3 * length},
                                                 {"head_diameter", 0.06},
                                                 {"color", colorJson(1.0, 0.8, 0.1, 1.0)}}})},
                        {"cubes", json::array({{{"pose", poseJson(centre, Eigen::Quaterniond::Identity())},
                                                {"size", vectorJson(size)},
                                                {"color", colorJson(0.1, 0.9, 0.3, 0.25)}}})},
                        {"spheres", json::array({{{"pose", poseJson(c.centroid_m, Eigen::Quaterniond::Identity())},
                                                  {"size", vectorJson(Eigen::Vector3d::Constant(0.08))},
                                                  {"color", colorJson(1.0, 0.8, 0.1, 1.0)}}})},
                        {"cylinders", json::array()},
                        {"lines", json::array()},
                        {"triangles", json::array()},
                        {"texts", json::array()},
                        {"models", json::array()}});
  }
  const json deletions = json::array({{{"timestamp", stampJson(time_ns)}, {"type", 1}, {"id", ""}}});
  return json{{"deletions", deletions}, {"entities", std::move(entities)}}.dump();
}

}  // namespace cenote::server::viewer
