// foxglove_schemas.h: the JSON schemas (encoding "jsonschema") of the viewer's channels: Foxglove's
// published message schemas (github.com/foxglove/schemas: SceneUpdate, FrameTransform,
// PosesInFrame, PointCloud, CompressedImage), restricted to the fields cenote sends, and cenote's own statistics.
// In the JSON encoding a Foxglove time is {sec, nsec}, bytes are base64 text.
// Threads: constant strings.
#pragma once

#include <string>

namespace cenote::server::viewer {

const std::string& sceneUpdateSchema();
const std::string& frameTransformSchema();
const std::string& posesInFrameSchema();
const std::string& pointCloudSchema();
const std::string& compressedImageSchema();
const std::string& mapStatsSchema();  // "cenote.MapStats"

}  // namespace cenote::server::viewer
