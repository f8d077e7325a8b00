#include "common/yaml_section.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "tests/support/error_message.h"

namespace cenote {
namespace {

TEST(YamlSection, ReadsPresentKeysAndKeepsDefaultsForAbsentOnes) {
  YamlSection root(YAML::Load("stereo: {window_px: 5}"), "", "test.yaml");
  YamlSection stereo = root.section("stereo");
  int window = 3, paths = 4;
  stereo.read("window_px", window);
  stereo.read("num_paths", paths);
  EXPECT_NO_THROW(stereo.finish());
  EXPECT_NO_THROW(root.finish());
  EXPECT_EQ(window, 5);
  EXPECT_EQ(paths, 4);
}

TEST(YamlSection, UnknownKeyIsAnErrorNamingFileAndDottedKey) {
  YamlSection root(YAML::Load("stereo: {window_sise: 5}"), "", "config/x.yaml");
  YamlSection stereo = root.section("stereo");
  int window = 3;
  stereo.read("window_px", window);
  try {
    stereo.finish();
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "config/x.yaml: unknown configuration key(s): stereo.window_sise");
  }
}

TEST(YamlSection, AKeyThatIsNotANameIsAnErrorNotACrash) {
  // The config fuzzer's find: a complex key (a mapping) in a section.
  YamlSection root(YAML::Load("server:\n  ? batch: 5\n  : 1\n"), "", "c.yaml");
  YamlSection server = root.section("server");
  EXPECT_EQ(test::errorMessage([&] { server.finish(); }), "c.yaml: server has a key that is not a name: batch: 5");
}

TEST(YamlSection, WrongTypeIsAnErrorNamingKeyAndExpectedType) {
  YamlSection root(YAML::Load("window_px: three"), "stereo", "c.yaml");
  int window = 3;
  try {
    root.read("window_px", window);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "c.yaml: stereo.window_px = 'three': expected an integer");
  }
  EXPECT_EQ(window, 3);
}

TEST(YamlSection, SectionThatIsNotAMappingIsAnError) {
  EXPECT_THROW(YamlSection(YAML::Load("[1, 2]"), "stereo", "c.yaml"), Error);
}

TEST(LoadYamlFile, MissingFileAndBrokenYamlAreErrors) {
  EXPECT_THROW(loadYamlFile("/nonexistent/cenote.yaml"), Error);
  const std::string path = testing::TempDir() + "/broken.yaml";
  std::ofstream(path) << "stereo: {window_px: [1, 2\n";
  EXPECT_THROW(loadYamlFile(path), Error);
}

}  // namespace
}  // namespace cenote
