#include "common/error.h"

#include <gtest/gtest.h>

#include <cerrno>
#include <filesystem>
#include <fstream>

namespace cenote {
namespace {

TEST(Error, PlainErrorIsInvalidArgument) {
  const Error e("stereo: window_px = 4: must be odd");
  EXPECT_EQ(e.kind(), ErrorKind::kInvalidArgument);
  EXPECT_STREQ(e.what(), "stereo: window_px = 4: must be odd");
}

TEST(Error, DerivedTypesCarryTheirKindAndAreCaughtAsError) {
  const auto kindOf = [](auto thrown) {
    try {
      throw thrown;
    } catch (const Error& e) {
      EXPECT_STREQ(e.what(), "m");
      return e.kind();
    }
  };
  EXPECT_EQ(kindOf(NotFoundError("m")), ErrorKind::kNotFound);
  EXPECT_EQ(kindOf(ResourceExhaustedError("m")), ErrorKind::kResourceExhausted);
  EXPECT_EQ(kindOf(IoError("m")), ErrorKind::kIoFailure);
  EXPECT_EQ(kindOf(FailedPreconditionError("m")), ErrorKind::kFailedPrecondition);
}

TEST(Error, KindsHaveNames) {
  EXPECT_STREQ(toString(ErrorKind::kInvalidArgument), "invalid argument");
  EXPECT_STREQ(toString(ErrorKind::kNotFound), "not found");
  EXPECT_STREQ(toString(ErrorKind::kResourceExhausted), "resource exhausted");
  EXPECT_STREQ(toString(ErrorKind::kIoFailure), "I/O failure");
  EXPECT_STREQ(toString(ErrorKind::kFailedPrecondition), "failed precondition");
}

// What `thrower` throws, as an Error.
template <typename Thrower>
Error caught(Thrower&& thrower) {
  try {
    thrower();
  } catch (const Error& e) {
    return e;
  }
  ADD_FAILURE() << "nothing was thrown";
  return Error("nothing was thrown");
}

TEST(Error, FullDiskIsResourceExhaustedOtherWriteFailuresAreIo) {
  EXPECT_EQ(ioErrorKind(ENOSPC), ErrorKind::kResourceExhausted);
  EXPECT_EQ(ioErrorKind(EDQUOT), ErrorKind::kResourceExhausted);
  EXPECT_EQ(ioErrorKind(EFBIG), ErrorKind::kResourceExhausted);  // a file size limit (ulimit -f)
  EXPECT_EQ(ioErrorKind(EIO), ErrorKind::kIoFailure);
  EXPECT_EQ(ioErrorKind(0), ErrorKind::kIoFailure);
  EXPECT_EQ(ioErrorKind(ENOENT), ErrorKind::kIoFailure);
  EXPECT_EQ(ioErrorKind(ENOENT, true), ErrorKind::kNotFound);
  const Error full = caught([] { throwWriteError("/maps/map.vdb", "write failed (disk full?)", ENOSPC); });
  EXPECT_STREQ(full.what(), "cannot write /maps/map.vdb: write failed (disk full?)");
  EXPECT_EQ(full.kind(), ErrorKind::kResourceExhausted);
  EXPECT_THROW(throwWriteError("/maps/map.vdb", "write failed (disk full?)", ENOSPC), ResourceExhaustedError);
  EXPECT_THROW(throwWriteError("/maps/map.vdb", "cannot create file"), IoError);
  EXPECT_EQ(caught([] { throwWriteError("/maps/map.vdb", "cannot create file"); }).kind(), ErrorKind::kIoFailure);
}

TEST(Error, ReadErrorOfAMissingFileIsNotFoundOfAnExistingOneIo) {
  const std::string dir = testing::TempDir();
  const std::string missing = dir + "/error_test_missing.txt";
  EXPECT_THROW(throwReadError(missing), NotFoundError);
  const Error absent = caught([&] { throwReadError(missing); });
  EXPECT_EQ(absent.kind(), ErrorKind::kNotFound);
  EXPECT_EQ(std::string(absent.what()), "cannot read " + missing + ": no such file");
  const std::string present = dir + "/error_test_present.txt";
  std::ofstream(present) << "x";
  EXPECT_THROW(throwReadError(present), IoError);
  const Error unreadable = caught([&] { throwReadError(present, "not readable", "trajectory "); });
  EXPECT_EQ(unreadable.kind(), ErrorKind::kIoFailure);
  EXPECT_EQ(std::string(unreadable.what()), "cannot read trajectory " + present + ": not readable");
  std::filesystem::remove(present);
}

}  // namespace
}  // namespace cenote
