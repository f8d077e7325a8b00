#include "common/atomic_file.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "tests/support/scratch_dir.h"

namespace cenote {
namespace {

namespace fs = std::filesystem;

fs::path freshDirectory(const std::string& name) { return test::freshScratchDirectory("atomic_file_test_" + name); }

std::string contentsOf(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

size_t filesIn(const fs::path& dir) {
  size_t n = 0;
  for ([[maybe_unused]] const auto& entry : fs::directory_iterator(dir)) ++n;
  return n;
}

TEST(AtomicFile, TemporaryNameKeepsTheExtensionAndIsRecognised) {
  const std::string pid = std::to_string(::getpid());
  EXPECT_EQ(temporaryPathFor("/maps/map.vdb"), "/maps/map.tmp-" + pid + ".vdb");
  EXPECT_EQ(temporaryPathFor("rig.yaml"), "rig.tmp-" + pid + ".yaml");
  EXPECT_EQ(temporaryPathFor("/maps/port"), "/maps/port.tmp-" + pid);
  EXPECT_TRUE(isTemporaryPath(temporaryPathFor("/maps/map.vdb")));
  EXPECT_TRUE(isTemporaryPath("/maps/map.mesh.tmp-12.ply"));
  EXPECT_FALSE(isTemporaryPath("/maps/map.vdb"));
  EXPECT_FALSE(isTemporaryPath("/maps/map.tmp-.vdb"));
  EXPECT_FALSE(isTemporaryPath("/maps/map.tmp-12a.vdb"));
}

TEST(AtomicFile, WritesTheWholeFileAndLeavesNoTemporary) {
  for (const Durability durability : {Durability::kDurable, Durability::kFast}) {
    const fs::path dir = freshDirectory("whole");
    const fs::path path = dir / "report.json";
    std::ofstream(path) << "old contents that are longer than the new";
    writeFileAtomically(path.string(), "{}\n", durability);
    EXPECT_EQ(contentsOf(path), "{}\n");
    EXPECT_EQ(filesIn(dir), 1u) << "a temporary file was left beside " << path;
  }
}

TEST(AtomicFile, MissingDirectoryIsAnIoErrorThatNamesTheTarget) {
  const fs::path dir = freshDirectory("missing");
  const std::string path = (dir / "absent" / "map.vdb").string();
  try {
    writeFileAtomically(path, "x", Durability::kDurable);
    FAIL() << "a write into a missing directory succeeded";
  } catch (const IoError& e) {
    EXPECT_EQ(std::string(e.what()), "cannot write " + path + ": cannot create file");
    EXPECT_EQ(e.kind(), ErrorKind::kIoFailure);
  }
  EXPECT_EQ(filesIn(dir), 0u);
}

// The Error that writeAtomically throws when its writer writes half a file, then throws `thrown`.
template <typename Exception>
Error errorOfHalfWrite(const std::string& path, Durability durability, const Exception& thrown) {
  try {
    writeAtomically(path, durability, [&](const std::string& temp) {
      std::ofstream(temp) << "half";
      throw thrown;
    });
  } catch (const Error& e) {
    return e;
  }
  ADD_FAILURE() << "the writer's exception was swallowed";
  return Error("");
}

TEST(AtomicFile, FailedWriterLeavesNeitherTargetNorTemporary) {
  const fs::path dir = freshDirectory("failed");
  const std::string path = (dir / "map.vdb").string();
  // A cenote::Error from the writer passes unchanged.
  const Error passed = errorOfHalfWrite(path, Durability::kDurable, ResourceExhaustedError("map: too many voxels"));
  EXPECT_STREQ(passed.what(), "map: too many voxels");
  EXPECT_EQ(passed.kind(), ErrorKind::kResourceExhausted);
  EXPECT_EQ(filesIn(dir), 0u);
  // Any other exception becomes "cannot write <path>: <what>", an I/O failure.
  const Error wrapped = errorOfHalfWrite(path, Durability::kFast, std::runtime_error("library said no"));
  EXPECT_EQ(std::string(wrapped.what()), "cannot write " + path + ": library said no");
  EXPECT_EQ(wrapped.kind(), ErrorKind::kIoFailure);
  EXPECT_EQ(filesIn(dir), 0u);
}

TEST(AtomicFile, RenameOntoADirectoryFailsAndRemovesTheTemporary) {
  const fs::path dir = freshDirectory("rename");
  const fs::path path = dir / "taken";
  fs::create_directories(path / "inside");  // a non-empty directory cannot be replaced by a file
  try {
    writeFileAtomically(path.string(), "x", Durability::kDurable);
    FAIL() << "a file replaced a directory";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()).rfind("cannot write " + path.string() + ": ", 0), 0u) << e.what();
    EXPECT_EQ(e.kind(), ErrorKind::kIoFailure);
  }
  EXPECT_EQ(filesIn(dir), 1u);
  EXPECT_TRUE(fs::is_directory(path));
}

}  // namespace
}  // namespace cenote
