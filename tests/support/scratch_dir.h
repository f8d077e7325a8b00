// scratch_dir.h: a fresh, empty directory for one test, under the test program's own scratch
// directory (gtest's TempDir(), which tests/CMakeLists.txt points at the build tree).
// Threads: call from the test's thread; each test uses its own name.
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

namespace cenote::test {

// Removes whatever an earlier run left under `name` and creates it empty.
inline std::filesystem::path freshScratchDirectory(const std::string& name) {
  const std::filesystem::path dir = std::filesystem::path(testing::TempDir()) / name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

}  // namespace cenote::test
