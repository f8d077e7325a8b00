#include "server/viewer/foxglove_schemas.h"

#include <nlohmann/json.hpp>

namespace cenote::server::viewer {
namespace {

using nlohmann::json;

json number() { return {{"type", "number"}}; }
json integer() { return {{"type", "integer"}}; }
json string() { return {{"type", "string"}}; }
json boolean() { return {{"type", "boolean"}}; }
json arrayOf(json item) { return {{"type", "array"}, {"items", std::move(item)}}; }
json object(const std::string& title, json properties) {
  return {{"title", title}, {"type", "object"}, {"properties", std::move(properties)}};
}

json base64Bytes() {
  json bytes = string();
  bytes["contentEncoding"] = "base64";
  return bytes;
}
json time(const std::string& title) { return object(title, {{"sec", integer()}, {"nsec", integer()}}); }
json vector3() { return object("foxglove.Vector3", {{"x", number()}, {"y", number()}, {"z", number()}}); }
json quaternion() {
  return object("foxglove.Quaternion", {{"x", number()}, {"y", number()}, {"z", number()}, {"w", number()}});
}
json pose() { return object("foxglove.Pose", {{"position", vector3()}, {"orientation", quaternion()}}); }
json color() { return object("foxglove.Color", {{"r", number()}, {"g", number()}, {"b", number()}, {"a", number()}}); }

json sceneEntity() {
  const json cube = object("foxglove.CubePrimitive", {{"pose", pose()}, {"size", vector3()}, {"color", color()}});
  const json sphere = object("foxglove.SpherePrimitive", {{"pose", pose()}, {"size", vector3()}, {"color", color()}});
  const json arrow = object("foxglove.ArrowPrimitive", {{"pose", pose()},
                                                        {"shaft_length", number()},
                                                        {"shaft_diameter", number()},
                                                        {"head_length", number()},
                                                        {"head_diameter", number()},
                                                        {"color", color()}});
  const json metadata = object("foxglove.KeyValuePair", {{"key", string()}, {"value", string()}});
  return object("foxglove.SceneEntity", {{"timestamp", time("time")},
                                         {"frame_id", string()},
                                         {"id", string()},
                                         {"lifetime", time("duration")},
                                         {"frame_locked", boolean()},
                                         {"metadata", arrayOf(metadata)},
                                         {"arrows", arrayOf(arrow)},
                                         {"cubes", arrayOf(cube)},
                                         {"spheres", arrayOf(sphere)},
                                         {"cylinders", arrayOf(json::object())},
                                         {"lines", arrayOf(json::object())},
                                         {"triangles", arrayOf(json::object())},
                                         {"texts", arrayOf(json::object())},
                                         {"models", arrayOf(json::object())}});
}

}  // namespace

const std::string& sceneUpdateSchema() {
  static const std::string schema = [] {
    const json deletion = object(
        "foxglove.SceneEntityDeletion",
        {{"timestamp", time("time")},
         {"type",
          {{"title", "foxglove.SceneEntityDeletionType"},
           {"description", "0: MATCHING_ID, 1: ALL"},
           {"oneOf", json::array({{{"title", "MATCHING_ID"}, {"const", 0}}, {{"title", "ALL"}, {"const", 1}}})}}},
         {"id", string()}});
    return object("foxglove.SceneUpdate", {{"deletions", arrayOf(deletion)}, {"entities", arrayOf(sceneEntity())}}).dump();
  }();
  return schema;
}

const std::string& frameTransformSchema() {
  static const std::string schema = object("foxglove.FrameTransform", {{"timestamp", time("time")},
                                                                       {"parent_frame_id", string()},
                                                                       {"child_frame_id", string()},
                                                                       {"translation", vector3()},
                                                                       {"rotation", quaternion()}})
                                        .dump();
  return schema;
}

const std::string& posesInFrameSchema() {
  static const std::string schema = object(
                                        "foxglove.PosesInFrame",
                                        {{"timestamp", time("time")}, {"frame_id", string()}, {"poses", arrayOf(pose())}})
                                        .dump();
  return schema;
}

const std::string& pointCloudSchema() {
  static const std::string schema = [] {
    const json field = object("foxglove.PackedElementField",
                              {{"name", string()},
                               {"offset", integer()},
                               {"type",
                                {{"title", "foxglove.NumericType"},
                                 {"description", "1: UINT8, 7: FLOAT32 (foxglove.NumericType)"},
                                 {"type", "integer"}}}});
    return object("foxglove.PointCloud", {{"timestamp", time("time")},
                                          {"frame_id", string()},
                                          {"pose", pose()},
                                          {"point_stride", integer()},
                                          {"fields", arrayOf(field)},
                                          {"data", base64Bytes()}})
        .dump();
  }();
  return schema;
}

const std::string& compressedImageSchema() {
  static const std::string schema =
      object("foxglove.CompressedImage",
             {{"timestamp", time("time")}, {"frame_id", string()}, {"data", base64Bytes()}, {"format", string()}})
          .dump();
  return schema;
}

const std::string& mapStatsSchema() {
  static const std::string schema = [] {
    const json stage = object("cenote.StageRate",
                              {{"name", string()}, {"median_ms", number()}, {"fps", number()}, {"frames", integer()}});
    return object("cenote.MapStats", {{"timestamp", time("time")},
                                      {"voxel_size_m", number()},
                                      {"occupied", integer()},
                                      {"free", integer()},
                                      {"memory_bytes", integer()},
                                      {"map_version", integer()},
                                      {"batches", integer()},
                                      {"stages", arrayOf(stage)},
                                      {"integrated_fps", number()},
                                      {"bytes_sent", integer()},
                                      {"clients", integer()},
                                      {"client_dirty_blocks", integer()},
                                      {"client_coarse_blocks", integer()},
                                      {"client_stale_blocks", integer()}})
        .dump();
  }();
  return schema;
}

}  // namespace cenote::server::viewer
