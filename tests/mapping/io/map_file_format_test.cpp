// map_file_format_test.cpp: the one table from extension to map file format (map_file_format.h),
// case by case from map_file_format_cases.txt (the Python client's test reads the same file), and
// the texts of the refusals.
#include "mapping/io/map_file_format.h"

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "common/error.h"
#include "tests/support/error_message.h"

namespace cenote::mapping {
namespace {

std::string errorOf(const std::string& path, MapFileFormat requested) {
  return cenote::test::errorMessage([&] { resolveMapFileFormat(path, requested); });
}

TEST(MapFileFormat, EveryCaseOfTheSharedTable) {
  const std::string file = std::string(CENOTE_SOURCE_DIR) + "/tests/mapping/io/map_file_format_cases.txt";
  std::ifstream in(file);
  ASSERT_TRUE(in) << file;
  std::string line;
  int cases = 0;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    std::string path, requested, expected;
    ASSERT_TRUE(fields >> path >> requested >> expected) << "malformed line: " << line;
    const MapFileFormat asked = requested == "-" ? MapFileFormat::kUnspecified : parseMapFileFormat(requested);
    ++cases;
    if (expected == "error") {
      EXPECT_THROW(resolveMapFileFormat(path, asked), Error) << path << " with " << requested << ": expected a refusal";
    } else {
      try {
        EXPECT_STREQ(toString(resolveMapFileFormat(path, asked)), expected.c_str()) << path << " with " << requested;
      } catch (const Error& e) {
        ADD_FAILURE() << path << " with " << requested << ": expected " << expected << ", refused: " << e.what();
      }
    }
  }
  EXPECT_EQ(cases, 33);
}

TEST(MapFileFormat, NumbersAreTheWireEnumsAndNamesRoundTrip) {
  EXPECT_EQ(static_cast<int>(MapFileFormat::kUnspecified), 0);
  EXPECT_EQ(static_cast<int>(MapFileFormat::kVdb), 1);
  EXPECT_EQ(static_cast<int>(MapFileFormat::kBt), 2);
  EXPECT_EQ(static_cast<int>(MapFileFormat::kOt), 3);
  EXPECT_EQ(static_cast<int>(MapFileFormat::kMeshPly), 4);
  EXPECT_EQ(static_cast<int>(MapFileFormat::kPointsPly), 5);
  EXPECT_EQ(static_cast<int>(MapFileFormat::kPointsPcd), 6);
  for (int i = 1; i <= 6; ++i) {
    const auto f = static_cast<MapFileFormat>(i);
    EXPECT_EQ(parseMapFileFormat(toString(f)), f) << toString(f);
    EXPECT_EQ(mapFileFormatOf(std::string("x") + extensionOf(f)), f) << extensionOf(f);
  }
  EXPECT_EQ(parseMapFileFormat("points_ply"), MapFileFormat::kPointsPly);
  EXPECT_EQ(parseMapFileFormat(""), MapFileFormat::kUnspecified);
  EXPECT_THROW(parseMapFileFormat("ply"), Error);
}

TEST(MapFileFormat, RefusalsNameThePathAndBothFormats) {
  EXPECT_EQ(errorOf("map.vdb", MapFileFormat::kPointsPly),
            "map.vdb: the extension .vdb means format vdb, not points-ply (the format follows the extension: "
            ".vdb vdb, .bt bt, .ot ot, .mesh.ply mesh-ply, .points.ply points-ply, .pcd points-pcd, "
            ".ply mesh-ply or points-ply as given)");
  EXPECT_EQ(errorOf("mesh.ply", MapFileFormat::kUnspecified),
            "mesh.ply: a .ply file holds a mesh or points: name it .mesh.ply or .points.ply, or give the format "
            "mesh-ply or points-ply");
  EXPECT_NE(
      errorOf("m.xyz", MapFileFormat::kUnspecified).find("m.xyz: the extension .xyz names no map file format (.vdb vdb"),
      std::string::npos);
  EXPECT_NE(errorOf("m", MapFileFormat::kBt).find("m: no extension does not match format bt, which is written as .bt"),
            std::string::npos);
  EXPECT_NE(
      errorOf("m.ply", MapFileFormat::kVdb).find("m.ply: the extension .ply means format mesh-ply or points-ply, not vdb"),
      std::string::npos);
}

}  // namespace
}  // namespace cenote::mapping
